// tillpath's service worker: the page opens with no network once it has been opened.
//
// The app shell (the page, its script, styles, icons, the translations) and the map libraries
// are cached when the worker installs and refreshed whenever they are fetched online
// (network first, the cache when the network fails). The API is never cached: planning needs
// the server, and the page says so when it cannot reach it. Map tiles are not cached either
// (other servers, and far too many).

// The server fills these in (app/routers/pages.py): every file of static/, the libraries the
// page loads and the catalogs, and a version that changes when any of them does.
const CACHE = "tillpath-shell-" + /*VERSION*/ "dev";
const SCOPE = new URL(self.registration.scope);

/** Paths below the scope that make up the shell. */
const SHELL = /*SHELL*/ [""].map((path) => new URL(path, SCOPE).href);

/** How long a request for the shell waits for the network before the cache answers [ms]. */
const NETWORK_TIMEOUT_MS = 4000;

self.addEventListener("install", (event) => {
  event.waitUntil(
    caches
      .open(CACHE)
      // One by one, so a missing optional file does not stop the rest from being cached.
      .then((cache) => Promise.all(SHELL.map((url) => cache.add(url).catch(() => null))))
      .then(() => self.skipWaiting()),
  );
});

self.addEventListener("activate", (event) => {
  event.waitUntil(
    caches
      .keys()
      .then((keys) =>
        Promise.all(keys.filter((key) => key.startsWith("tillpath-shell-") && key !== CACHE).map((key) => caches.delete(key))),
      )
      .then(() => self.clients.claim()),
  );
});

function isShell(url) {
  if (url.origin !== SCOPE.origin || !url.pathname.startsWith(SCOPE.pathname)) return false;
  const path = url.pathname.slice(SCOPE.pathname.length);
  return path === "" || /^(static|vendor|i18n)\//.test(path) || path === "manifest.webmanifest";
}

async function networkFirst(request) {
  const cache = await caches.open(CACHE);
  const key = request.mode === "navigate" ? new URL("", SCOPE).href : request;
  try {
    const response = await Promise.race([
      fetch(request),
      new Promise((_, reject) => setTimeout(() => reject(new Error("timeout")), NETWORK_TIMEOUT_MS)),
    ]);
    if (response.ok) cache.put(key, response.clone());
    return response;
  } catch (error) {
    const cached = await cache.match(key, { ignoreVary: true });
    if (cached) return cached;
    throw error;
  }
}

self.addEventListener("fetch", (event) => {
  const { request } = event;
  if (request.method !== "GET") return;
  const url = new URL(request.url);
  const navigation = request.mode === "navigate" && url.origin === SCOPE.origin && url.pathname === SCOPE.pathname;
  if (navigation || isShell(url)) event.respondWith(networkFirst(request));
});
