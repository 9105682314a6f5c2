// In the paddy, with no signal: the service worker (sw.js) keeps the page and its libraries,
// and plans saved while the server cannot be reached wait here (localStorage) until it can.

import { ApiError } from "./api.js";
import { KEYS, readStored, store } from "./storage.js";

/** How often waiting saves are tried again while the page is open [ms]. */
const RETRY_MS = 20_000;

/** Register the service worker (served at the site root, so it covers the page). */
export function registerServiceWorker(url) {
  if (!url || !("serviceWorker" in navigator)) return Promise.resolve(null);
  return navigator.serviceWorker.register(url).catch((error) => {
    // Plain HTTP on a farm network: browsers allow service workers on HTTPS and localhost only.
    console.warn("service worker not registered:", error?.message ?? error);
    return null;
  });
}

/** Saves waiting to be sent: `[{request, queuedAt}]`, oldest first. */
export function pendingSaves() {
  const queued = readStored(KEYS.outbox);
  return Array.isArray(queued) ? queued : [];
}

/** Keep `request` (a POST /api/plans body) until the server can be reached. */
export function queueSave(request) {
  const queued = pendingSaves();
  queued.push({ request, queuedAt: new Date().toISOString() });
  return store(KEYS.outbox, queued);
}

/**
 * Send the waiting saves through `api.create`, oldest first, stopping at the first that cannot
 * be sent (still offline). A save the server refuses (bad input) is dropped and reported.
 *
 * @returns {Promise<{sent: object[], refused: {request: object, error: ApiError}[], left: number}>}
 */
export async function flushSaves(api) {
  const sent = [];
  const refused = [];
  let queued = pendingSaves();
  while (queued.length > 0) {
    const [next] = queued;
    try {
      sent.push(await api.create(next.request));
    } catch (error) {
      if (error instanceof ApiError && error.status >= 400 && error.status < 500) {
        refused.push({ request: next.request, error });
      } else {
        break; // not reachable yet: try again later
      }
    }
    queued = queued.slice(1);
    store(KEYS.outbox, queued);
  }
  return { sent, refused, left: queued.length };
}

/**
 * Send waiting saves when the network comes back (and now, and every RETRY_MS while some wait).
 *
 * @param {object} options
 * @param {PlansApi} options.api
 * @param {(result: object) => void} options.onFlushed Called after a flush that sent or refused some.
 * @param {(online: boolean) => void} options.onConnectionChange
 * @param {() => Promise<boolean>} [options.beforeFlush] Sign in first; false: not yet.
 */
export function watchConnection({ api, onFlushed, onConnectionChange, beforeFlush = async () => true }) {
  let running = false;
  async function flush() {
    if (running || pendingSaves().length === 0) return;
    running = true;
    try {
      if (!(await beforeFlush())) return;
      const result = await flushSaves(api);
      if (result.sent.length > 0 || result.refused.length > 0) onFlushed(result);
    } finally {
      running = false;
    }
  }
  window.addEventListener("online", () => {
    onConnectionChange(true);
    flush();
  });
  window.addEventListener("offline", () => onConnectionChange(false));
  setInterval(flush, RETRY_MS);
  flush();
  return { flush };
}
