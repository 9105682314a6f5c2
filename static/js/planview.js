// Plans: the request from the page's inputs, the API's answer drawn with its figures, saved,
// opened and deleted plans. The API does all the planning (style.md §4).

import { ApiError } from "./api.js";
import { saveDraft } from "./draft.js";
import { endPlacing, fieldFromPolygon, fieldGeometry, markerLonLat, placeMarker } from "./fieldedit.js";
import { DEFAULT_SPEED_MPS, fillForm, numberInput } from "./form.js";
import { polygonOf } from "./fieldfile.js";
import {
  formatAngle,
  formatArea,
  formatDuration,
  formatLength,
  formatNumber,
  formatPercent,
} from "./format.js";
import { t, tn } from "./i18n.js";
import {
  clearError,
  PHONE_QUERY,
  setStatus,
  showError,
  showFailure,
  showResultOnPhone,
  updateNotice,
} from "./messages.js";
import { queueSave } from "./offline.js";
import { state, ui } from "./pagestate.js";
import { drawPlan } from "./planlayer.js";
import { planTitle } from "./savedplans.js";
import { fillVehicle, vehicleRequest } from "./vehicle.js";

/** The request body of product.md §3 from the page; null (with an alert) when incomplete. */
export function buildRequest() {
  const field = fieldGeometry();
  if (!field) return null;
  const inputs = {
    interval_m: numberInput(ui.interval, t("Interval (m)"), { required: true, example: "4" }),
    angle_deg: numberInput(ui.angle, t("Line angle (°)"), { example: t("90 (east–west), or leave it empty") }),
    speed_mps: numberInput(ui.speed, t("Speed (m/s)"), { fallback: DEFAULT_SPEED_MPS, example: "0.56" }),
  };
  for (const [name, result] of Object.entries(inputs)) {
    if (result.error) {
      showError(result.error, name);
      return null;
    }
  }
  const machine = vehicleRequest();
  if (machine.error) {
    showError(machine.error, machine.input);
    return null;
  }
  return {
    ...machine,
    name: ui.planName.value.trim() || null,
    field,
    interval_m: inputs.interval_m.value,
    start: markerLonLat("start"),
    finish: markerLonLat("finish"),
    angle_deg: inputs.angle_deg.value,
    objective: ui.objective.value,
    headland_passes: Number.parseInt(ui.headland.value, 10),
    speed_mps: inputs.speed_mps.value,
  };
}

function renderSummary(stats) {
  const figures = {
    lines: formatNumber(stats.line_count),
    waypoints: formatNumber(stats.waypoint_count),
    area: formatArea(stats.area_m2),
    length: formatLength(stats.path_length_m),
    time: formatDuration(stats.estimated_time_s),
    coverage: formatPercent(stats.coverage_ratio),
    angle: formatAngle(stats.angle_deg),
  };
  for (const [key, text] of Object.entries(figures)) {
    ui.summaryFigures.querySelector(`[data-stat="${key}"]`).textContent = text;
  }
  ui.summaryFigures.hidden = false;
  ui.summaryEmpty.hidden = true;
}

export function renderDownloads() {
  const id = state.savedId;
  ui.downloads.hidden = id == null;
  for (const link of ui.downloads.querySelectorAll("a[data-format]")) {
    if (id == null) link.removeAttribute("href");
    else link.href = state.api.exportUrl(id, link.dataset.format);
  }
}

export function removePlan() {
  state.planDrawing?.remove();
  state.planDrawing = null;
  state.plan = null;
  state.savedId = null;
  ui.summaryFigures.hidden = true;
  ui.summaryEmpty.hidden = false;
  renderDownloads();
  state.saved?.markCurrent();
  state.checks?.planChanged(null);
}

export function showPlan(plan, { saved }) {
  state.planDrawing?.remove();
  state.plan = plan;
  state.savedId = saved ? plan.id : null;
  state.planDrawing = drawPlan(state.map, plan.geojson);
  renderSummary(plan.stats);
  renderDownloads();
  state.saved?.markCurrent();
  state.checks?.planChanged(state.savedId);
  saveDraft();
}

/** Fit `bounds`, keeping clear of the controls sheet when it covers the map on a phone. */
export function fitMap(bounds) {
  if (!bounds?.isValid()) return;
  const covered = PHONE_QUERY.matches && ui.app.classList.contains("panel-open") ? ui.panel.offsetHeight : 0;
  // No animation: the field appears at once, and what is on screen is where it stays.
  state.map.fitBounds(bounds, {
    paddingTopLeft: [60, 40],
    paddingBottomRight: [30, 30 + covered],
    maxZoom: 21,
    animate: false,
  });
}

function setBusy(busy) {
  ui.generate.disabled = busy;
  ui.save.disabled = busy;
  ui.summary.setAttribute("aria-busy", String(busy));
}

/** Saving with no connection: keep the plan on the phone and send it when the network is back. */
function saveLater(request) {
  if (!queueSave(request)) return false;
  updateNotice();
  setStatus(t("No connection: the plan is kept on this phone and will be saved when the connection is back."));
  return true;
}

/** Ask the API for a plan from the page's inputs; `save` stores it too. */
export async function generate({ save = false, quiet = false } = {}) {
  endPlacing();
  clearError();
  const request = buildRequest();
  if (!request) {
    // What is drawn must match what was asked: an old path beside "not a number" misleads.
    state.requestSeq += 1;
    removePlan();
    saveDraft();
    return;
  }
  state.requestSeq += 1;
  const seq = state.requestSeq;
  setBusy(true);
  setStatus(save ? t("Saving the plan…") : t("Planning the path…"), { sticky: true });
  try {
    const plan = save ? await state.api.create(request) : await state.api.preview(request);
    if (seq !== state.requestSeq) return; // a newer request (a marker dragged again) wins
    const sheetWasOpen = ui.app.classList.contains("panel-open");
    showPlan(plan, { saved: save });
    const lines = tn("{count} line", "{count} lines", plan.stats.line_count, { count: plan.stats.line_count });
    const result = save ? t("Saved “{name}”.", { name: planTitle(plan) }) : t("Path ready: {lines}.", { lines });
    if (quiet) setStatus("");
    else showResultOnPhone(result);
    if (!quiet) fitMapToPlanOnPhone(sheetWasOpen);
    if (save) {
      await state.saved.refresh();
      state.fields?.refresh(); // a saved plan may have added a field to the registry
    }
  } catch (error) {
    if (seq === state.requestSeq) {
      setStatus("");
      if (save && error instanceof ApiError && error.status === 0 && saveLater(request)) return;
      // What is drawn must match what was asked, or be nothing: a path for the old start or
      // the old boundary beside an error would mislead.
      removePlan();
      saveDraft();
      if (!quiet) showFailure(error);
    }
  } finally {
    if (seq === state.requestSeq) setBusy(false);
  }
}

/**
 * On a phone the sheet folds after a result: when it was open, it hid part of the map, so fit
 * the whole path to the screen it leaves; and whenever the path is partly off screen.
 */
function fitMapToPlanOnPhone(sheetWasOpen) {
  if (!PHONE_QUERY.matches || !state.planDrawing?.bounds) return;
  if (sheetWasOpen || !state.map.getBounds().contains(state.planDrawing.bounds)) fitMap(state.planDrawing.bounds);
}

/** One edit can fire several events (a cut is also an edit): plan once they have settled. */
const REPLAN_DELAY_MS = 120;
let replanTimer = null;

/** Moving the start, the finish or a corner changes the best path: plan again if one is shown. */
export function replanIfPlanned() {
  if (!state.plan) return;
  clearTimeout(replanTimer);
  replanTimer = setTimeout(() => {
    if (state.plan) generate();
  }, REPLAN_DELAY_MS);
}

export async function openPlan(id, { quiet = false } = {}) {
  endPlacing();
  clearError();
  try {
    const plan = await state.api.read(id);
    const request = plan.request ?? {};
    state.restoring = true;
    try {
      fillForm(ui, request, plan.name);
      fillVehicle(request);
      fieldFromPolygon(polygonOf(request.field));
      placeMarker("start", request.start);
      placeMarker("finish", request.finish);
    } finally {
      state.restoring = false;
    }
    showPlan(plan, { saved: true });
    if (!quiet) {
      fitMap(state.planDrawing.bounds ?? state.field.getBounds());
      showResultOnPhone(t("Opened “{name}”.", { name: planTitle(plan) }));
    }
  } catch (error) {
    if (quiet) {
      // The draft's stored plan is gone or the server is away: the draft itself stays.
      if (!(error instanceof ApiError && error.status === 0)) saveDraft();
      return;
    }
    showFailure(error);
  }
}

export async function deletePlan(id, title) {
  if (!window.confirm(t("Delete the plan “{name}”? This cannot be undone.", { name: title }))) return;
  clearError();
  try {
    await state.api.remove(id);
    if (state.savedId === id) {
      // The path stays on the map, but it is no longer stored: nothing left to download.
      state.savedId = null;
      renderDownloads();
      state.checks?.planChanged(null);
      saveDraft();
    }
    setStatus(t("Deleted “{name}”.", { name: title }));
  } catch (error) {
    if (!(error instanceof ApiError && error.status === 404)) showFailure(error);
  }
  await state.saved.refresh();
}
