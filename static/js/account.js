// Accounts on the page (product.md §12): the sign-in (or first-account) screen, who is signed
// in, the organisation switch, sign-out, and the settings with API and device tokens.
// The session lives in an HttpOnly cookie; every write sends the session's CSRF token.

import { friendlyError } from "./format.js";
import { t } from "./i18n.js";

const $ = (id) => document.getElementById(id);

let csrfToken = null;

/** Headers every write made with the session cookie must carry (empty before sign-in). */
export function csrfHeaders() {
  return csrfToken ? { "X-CSRF-Token": csrfToken } : {};
}

async function call(url, { method = "GET", body } = {}) {
  const headers = {
    Accept: "application/json",
    "Accept-Language": document.documentElement.lang || "en",
    ...(method === "GET" ? {} : csrfHeaders()),
  };
  if (body !== undefined) headers["Content-Type"] = "application/json";
  const response = await fetch(url, {
    method,
    headers,
    credentials: "same-origin",
    body: body === undefined ? undefined : JSON.stringify(body),
  });
  let data = null;
  if (response.status !== 204) {
    try {
      data = await response.json();
    } catch {
      data = null;
    }
  }
  return { ok: response.ok, status: response.status, data };
}

function formatTime(text) {
  return text ? new Date(text).toLocaleString(document.documentElement.lang || undefined) : t("never");
}

/** Show the sign-in screen (or the first-account one) until the person is signed in. */
function askToSignIn(apiUrl, firstAccount) {
  const screen = $("auth-screen");
  document.body.append(screen); // above everything, whatever the panel's layout
  $("auth-title").textContent = firstAccount ? t("Create the first account") : t("Sign in");
  $("auth-hint").textContent = firstAccount
    ? t("This server has no account yet. Choose a username and a password (at least 8 characters): you will own its organisation.")
    : t("Sign in to see your organisation's fields and plans.");
  $("auth-submit").textContent = firstAccount ? t("Create account") : t("Sign in");
  $("auth-organisation-row").hidden = !firstAccount;
  $("auth-password").autocomplete = firstAccount ? "new-password" : "current-password";
  screen.hidden = false;
  $("auth-username").focus();
  return new Promise((resolve) => {
    $("auth-form").addEventListener("submit", async (event) => {
      event.preventDefault();
      $("auth-error").textContent = "";
      const body = { username: $("auth-username").value.trim(), password: $("auth-password").value };
      if (firstAccount) body.organisation = $("auth-organisation").value.trim() || "default";
      const answer = await call(`${apiUrl}/auth/${firstAccount ? "signup" : "login"}`, {
        method: "POST",
        body,
      });
      if (!answer.ok) {
        // The server words it in the page's language; the input gets its label (format.js).
        $("auth-error").textContent = friendlyError(answer.status, answer.data?.detail).message;
        return;
      }
      screen.hidden = true;
      $("auth-password").value = "";
      resolve(answer.data);
    });
  });
}

function showAccount(apiUrl, me) {
  csrfToken = me.csrf_token ?? null;
  $("account").hidden = false;
  $("account-user").textContent = `${me.user.username} (${me.organisation.role})`;
  const select = $("account-organisation");
  select.replaceChildren(
    ...me.organisations.map((org) => {
      const option = document.createElement("option");
      option.value = String(org.id);
      option.textContent = org.name;
      option.selected = org.id === me.organisation.id;
      return option;
    }),
  );
  select.hidden = me.organisations.length < 2;
}

function tokenItem(apiUrl, token, refresh) {
  const item = document.createElement("li");
  const label = document.createElement("span");
  const kind = token.kind === "device" ? t("device") : t("personal");
  label.textContent = t("{name} ({kind}, {prefix}…) · last used {time}", {
    name: token.name,
    kind,
    prefix: token.prefix,
    time: formatTime(token.last_used_at),
  });
  if (token.revoked_at) label.className = "revoked";
  item.append(label);
  if (!token.revoked_at) {
    const revoke = document.createElement("button");
    revoke.type = "button";
    revoke.className = "quiet small";
    revoke.textContent = t("Revoke");
    revoke.setAttribute("aria-label", t("Revoke {name}", { name: token.name }));
    revoke.addEventListener("click", async () => {
      await call(`${apiUrl}/tokens/${encodeURIComponent(token.id)}`, { method: "DELETE" });
      refresh();
    });
    item.append(revoke);
  }
  return item;
}

async function refreshTokens(apiUrl) {
  const answer = await call(`${apiUrl}/tokens`);
  const items = answer.ok ? answer.data.items : [];
  const refresh = () => refreshTokens(apiUrl);
  $("token-list").replaceChildren(...items.map((token) => tokenItem(apiUrl, token, refresh)));
  $("token-empty").hidden = items.length > 0;
}

function wireAccount(apiUrl, me) {
  $("account-organisation").addEventListener("change", async (event) => {
    const answer = await call(`${apiUrl}/me/organisation`, {
      method: "PUT",
      body: { organisation_id: Number(event.target.value) },
    });
    if (answer.ok) window.location.reload();
  });
  $("sign-out").addEventListener("click", async () => {
    await call(`${apiUrl}/auth/logout`, { method: "POST" });
    window.location.reload();
  });
  $("account-settings").addEventListener("click", () => {
    const settings = $("settings");
    settings.hidden = !settings.hidden;
    $("account-settings").setAttribute("aria-expanded", String(!settings.hidden));
    if (!settings.hidden) refreshTokens(apiUrl);
  });
  $("token-device").disabled = me.organisation.role !== "owner";
  $("token-form").addEventListener("submit", async (event) => {
    event.preventDefault();
    const answer = await call(`${apiUrl}/tokens`, {
      method: "POST",
      body: { name: $("token-name").value.trim(), device: $("token-device").checked },
    });
    if (!answer.ok) return;
    $("token-value").textContent = answer.data.token;
    $("token-new").hidden = false;
    $("token-name").value = "";
    refreshTokens(apiUrl);
  });
}

/**
 * Make sure someone is signed in: answer `/api/me`, after the sign-in screen if needed.
 * @param {string} apiUrl the API root (`…/api`)
 */
export async function signIn(apiUrl) {
  let answer = await call(`${apiUrl}/me`);
  if (answer.status === 401) {
    const setup = await call(`${apiUrl}/auth/setup`);
    await askToSignIn(apiUrl, Boolean(setup.data?.needs_first_account));
    answer = await call(`${apiUrl}/me`);
  }
  if (!answer.ok) throw new Error(answer.data?.detail ?? `HTTP ${answer.status}`);
  showAccount(apiUrl, answer.data);
  wireAccount(apiUrl, answer.data);
  return answer.data;
}
