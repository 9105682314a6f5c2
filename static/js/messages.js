// What the page says: the status over the map (it fades), errors in the alert region (they
// stay, pointing at the input concerned), the lasting notice (offline, saves waiting), and the
// controls sheet on a phone, which folds away to show a result.

import { ApiError } from "./api.js";
import { FieldFileError } from "./fieldfile.js";
import { friendlyError } from "./format.js";
import { t, tn } from "./i18n.js";
import { pendingSaves } from "./offline.js";

/** Narrow screens get the map full-screen and the controls in a sheet (see app.css). */
export const PHONE_QUERY = window.matchMedia("(max-width: 720px)");
/** Status messages fade after this long [ms]; prompts that wait for a tap stay. */
const STATUS_MS = 6000;

/** Which form control shows each API input (by id), to point at it when the API refuses it. */
const INPUT_CONTROLS = {
  name: "plan-name",
  interval_m: "interval",
  angle_deg: "angle",
  objective: "objective",
  headland_passes: "headland",
  speed_mps: "speed",
  vehicle: "vehicle",
  implement_width_m: "implement-width",
  pattern: "pattern",
};

const $ = (id) => document.getElementById(id);
const ui = {
  app: $("app"),
  panelToggle: $("panel-toggle"),
  alert: $("alert"),
  notice: $("notice"),
  status: $("status"),
};

let statusTimer = null;

/** Say `text` over the map; it fades after a while unless `sticky` (a prompt awaiting a tap). */
export function setStatus(text, { sticky = false } = {}) {
  clearTimeout(statusTimer);
  ui.status.textContent = text;
  ui.status.classList.remove("fading");
  if (text && !sticky) {
    statusTimer = setTimeout(() => {
      ui.status.classList.add("fading");
      statusTimer = setTimeout(() => {
        ui.status.textContent = "";
        ui.status.classList.remove("fading");
      }, 600);
    }, STATUS_MS);
  }
}

export function clearError() {
  ui.alert.textContent = "";
  for (const id of Object.values(INPUT_CONTROLS)) $(id)?.removeAttribute("aria-invalid");
}

/** Show a problem in the alert region and point at the control it concerns. */
export function showError(message, input = null) {
  clearError();
  ui.alert.textContent = message;
  setPanelOpen(true); // on a phone the alert would otherwise hide behind the map
  const control = input in INPUT_CONTROLS ? $(INPUT_CONTROLS[input]) : null;
  if (control) {
    control.setAttribute("aria-invalid", "true");
    control.focus();
  }
}

export function showFailure(error) {
  if (error instanceof ApiError) {
    const { message, input } = friendlyError(error.status, error.detail);
    showError(message, input);
  } else if (error instanceof FieldFileError) {
    showError(error.message);
  } else {
    console.error(error);
    showError(t("Something went wrong in the page: {problem}", { problem: error?.message ?? String(error) }));
  }
}

/** A lasting line at the top of the controls: offline, saves waiting to be sent. */
export function updateNotice() {
  const waiting = pendingSaves().length;
  const parts = [];
  if (!navigator.onLine) {
    parts.push(t("No connection. The page and your draft are kept on this phone; planning needs the server."));
  }
  if (waiting > 0) {
    parts.push(
      tn(
        "{count} saved plan is waiting to be sent; it goes out when the connection is back.",
        "{count} saved plans are waiting to be sent; they go out when the connection is back.",
        waiting,
        { count: waiting },
      ),
    );
  }
  ui.notice.textContent = parts.join(" ");
  ui.notice.hidden = parts.length === 0;
}

export function setPanelOpen(open) {
  ui.app.classList.toggle("panel-open", open);
  ui.panelToggle.setAttribute("aria-expanded", String(open));
}

/** On a phone, get the sheet out of the way when the next step is a tap on the map. */
export function revealMapOnPhone() {
  if (PHONE_QUERY.matches) setPanelOpen(false);
}

/** On a phone, fold the sheet to show a result, and say how to bring it back. */
export function showResultOnPhone(text) {
  if (PHONE_QUERY.matches) {
    setPanelOpen(false);
    setStatus(t("{result} Tap Controls for the figures.", { result: text }));
  } else {
    setStatus(text);
  }
}

