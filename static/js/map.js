// The map page: draw, walk or import a field, place start and finish, ask the API for a path,
// show it, save it, download it. The page holds what the person drew and typed (and keeps it on
// the phone as a draft); the API does all the planning (style.md §4), so nothing here computes
// geometry beyond drawing it. Every word shown goes through t() (i18n.js).

/* global L */

import { signIn } from "./account.js";
import { ApiError, ChecksApi, PlansApi, postForm } from "./api.js";
import { DEFAULT_SPEED_MPS, fillForm, fillFormValues, formValues, numberInput } from "./form.js";
import {
  clearError,
  PHONE_QUERY,
  revealMapOnPhone,
  setPanelOpen,
  setStatus,
  showError,
  showFailure,
  showResultOnPhone,
  updateNotice,
} from "./messages.js";
import { setUpChecks } from "./checks.js";
import { polygonOf } from "./fieldfile.js";
import { chooseField, closeFieldChooser, parseFieldFile } from "./fieldpicker.js";
import {
  formatAngle,
  formatArea,
  formatDuration,
  formatLength,
  formatNumber,
  formatPercent,
} from "./format.js";
import { setUpFields } from "./fields.js";
import { restoreLanguageChoice, switchLanguage, t, tapOrClick, tn } from "./i18n.js";
import { queueSave, registerServiceWorker, watchConnection } from "./offline.js";
import { createMap, FIELD_STYLE, setUpGeoman } from "./basemap.js";
import { drawPlan } from "./planlayer.js";
import { fillVehicle, setUpVehicle, vehicleRequest } from "./vehicle.js";
import { planTitle, setUpSavedPlans } from "./savedplans.js";
import { forget, KEYS, readStored, store } from "./storage.js";
import { goToCoordinates, setUpWalkControls } from "./walk.js";



const $ = (id) => document.getElementById(id);

const ui = {
  app: $("app"),
  panel: $("panel"),
  panelToggle: $("panel-toggle"),
  language: $("language"),
  drawField: $("draw-field"),
  importField: $("import-field"),
  importFile: $("import-file"),
  setStart: $("set-start"),
  setFinish: $("set-finish"),
  clearAll: $("clear-all"),
  gotoForm: $("goto-form"),
  goto: $("goto"),
  interval: $("interval"),
  angle: $("angle"),
  objective: $("objective"),
  headland: $("headland"),
  speed: $("speed"),
  planName: $("plan-name"),
  generate: $("generate"),
  save: $("save-plan"),
  summary: $("summary"),
  summaryEmpty: $("summary-empty"),
  summaryFigures: $("summary-figures"),
  downloads: $("downloads"),
};

const state = {
  map: null,
  api: null,
  field: null, // the editable L.Polygon
  markers: { start: null, finish: null },
  plan: null, // the last plan the API sent
  planDrawing: null, // what drawPlan returned, to remove it
  savedId: null, // the plan's id when what is shown is stored
  placing: null, // "start" | "finish" while waiting for a map click
  requestSeq: 0, // answers to superseded requests are dropped
  checks: null, // simulations and runs of the stored plan (checks.js)
  saved: null, // the Saved plans list (savedplans.js)
  fields: null, // the organisation's field registry (fields.js)
  parseUrl: null, // POST /api/fields/parse: the server's reader of field files
  importSeq: 0, // a newer import supersedes a field choice still open
  signedIn: false, // false while the server could not be reached to sign in (offline)
  walker: null, // Walk the boundary (walk.js)
  restoring: false, // while the draft is put back, changes are not stored again
};

/** A boundary whose edges cross (a bow tie) cannot be tilled as one field: say so at once. */
function checkSelfIntersection(layer) {
  if (layer.pm?.hasSelfIntersection?.()) {
    showError(
      t("Field: the boundary crosses itself (like a bow tie). Move the corners so that no edges cross, or draw the field again."),
    );
    return true;
  }
  return false;
}

// ---------------------------------------------------------------- field, start, finish

/** Make `layer` the field (one at a time), following its edits. */
function adoptField(layer, { replot }) {
  if (state.field && state.field !== layer) state.field.remove();
  state.field = layer;
  layer.setStyle(FIELD_STYLE);
  layer.on("pm:edit pm:dragend", () => {
    saveDraft();
    if (!checkSelfIntersection(layer)) replanIfPlanned();
  });
  if (replot) replanIfPlanned();
  else removePlan();
  saveDraft();
}

function fieldFromPolygon(polygon) {
  const layer = L.polygon(L.GeoJSON.coordsToLatLngs(polygon.coordinates, 1), FIELD_STYLE);
  layer.addTo(state.map);
  adoptField(layer, { replot: false });
  return layer;
}

/** The field as a GeoJSON Polygon, full precision; null (with an alert) when there is none. */
function fieldGeometry({ quiet = false } = {}) {
  if (!state.field) {
    if (!quiet) {
      showError(
        tapOrClick(
          t("Field: there is no field yet. Press Draw field and tap its corners on the map, or use Import field."),
          t("Field: there is no field yet. Press Draw field and click its corners on the map, or use Import field."),
        ),
      );
    }
    return null;
  }
  const geometry = state.field.toGeoJSON(false).geometry;
  if (geometry.type === "MultiPolygon") {
    if (geometry.coordinates.length === 1) return { type: "Polygon", coordinates: geometry.coordinates[0] };
    if (!quiet) showError(t("Field: the cut split the field into separate pieces. Plan one piece at a time: remove the others."));
    return null;
  }
  return geometry;
}

function endpointIcon(role) {
  return L.divIcon({
    className: `endpoint endpoint-${role}`,
    html: `<span><b>${role === "start" ? "S" : "F"}</b></span>`,
    iconSize: [30, 30],
    iconAnchor: [15, 34],
    tooltipAnchor: [0, -30],
  });
}

/** Put the start or finish marker at `latlng` (a Leaflet LatLng or `[lon, lat]`), or remove it. */
function placeMarker(role, position) {
  const old = state.markers[role];
  if (old) old.remove();
  state.markers[role] = null;
  if (!position) return;
  const latlng = Array.isArray(position) ? L.latLng(position[1], position[0]) : position;
  const title = role === "start" ? t("Start (drag to move)") : t("Finish (drag to move)");
  const marker = L.marker(latlng, {
    icon: endpointIcon(role),
    draggable: true,
    pmIgnore: true, // dragging is ours; Geoman's edit modes leave these alone
    title,
    zIndexOffset: 1000,
  }).addTo(state.map);
  // The pin's letter would be its accessible name; the title says what it is and what to do.
  marker.getElement()?.setAttribute("aria-label", title);
  marker.on("dragend", () => {
    saveDraft();
    replanIfPlanned();
  });
  state.markers[role] = marker;
}

function markerLonLat(role) {
  const marker = state.markers[role];
  if (!marker) return null;
  const { lat, lng } = marker.getLatLng();
  return [lng, lat];
}

function beginPlacing(role) {
  state.map.pm.disableDraw();
  state.placing = role;
  ui.app.classList.add("placing");
  ui.setStart.setAttribute("aria-pressed", String(role === "start"));
  ui.setFinish.setAttribute("aria-pressed", String(role === "finish"));
  const prompt =
    role === "start"
      ? tapOrClick(t("Tap the map where the tractor starts."), t("Click the map where the tractor starts."))
      : tapOrClick(t("Tap the map where the tractor must finish."), t("Click the map where the tractor must finish."));
  setStatus(prompt, { sticky: true });
  revealMapOnPhone();
}

function endPlacing() {
  if (!state.placing) return;
  state.placing = null;
  ui.app.classList.remove("placing");
  ui.setStart.setAttribute("aria-pressed", "false");
  ui.setFinish.setAttribute("aria-pressed", "false");
  setStatus("");
}

function onMapClick(event) {
  if (!state.placing) return;
  const role = state.placing;
  endPlacing();
  placeMarker(role, event.latlng);
  saveDraft();
  replanIfPlanned();
}

function startDrawing() {
  endPlacing();
  state.walker.end();
  clearError();
  state.map.pm.enableDraw("Polygon", { finishOn: null });
  setStatus(
    tapOrClick(
      t("Tap the corners of the field. Tap the first corner again to close it."),
      t("Click the corners of the field. Click the first corner again to close it."),
    ),
    { sticky: true },
  );
  revealMapOnPhone();
}

// ---------------------------------------------------------------- the form

/** The request body of product.md §3 from the page; null (with an alert) when incomplete. */
function buildRequest() {
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

// ---------------------------------------------------------------- the draft

/** Keep the field, the markers and the inputs on the phone: a reload or no network loses nothing. */
function saveDraft() {
  if (state.restoring) return;
  store(KEYS.draft, {
    field: state.field ? fieldGeometry({ quiet: true }) : null,
    start: markerLonLat("start"),
    finish: markerLonLat("finish"),
    form: formValues(ui),
    planned: state.plan != null,
    savedId: state.savedId,
  });
}

/** Put the draft back after a reload; open its stored plan, or plan it again, when online. */
function restoreDraft() {
  const draft = readStored(KEYS.draft);
  if (!draft) return;
  state.restoring = true;
  try {
    fillFormValues(ui, draft.form);
    if (draft.field?.type === "Polygon") fieldFromPolygon(draft.field);
    placeMarker("start", draft.start);
    placeMarker("finish", draft.finish);
  } finally {
    state.restoring = false;
  }
  if (draft.savedId != null) openPlan(draft.savedId, { quiet: true, keepDraft: true });
  else if (draft.planned && state.field && navigator.onLine) generate({ quiet: true });
}

// ---------------------------------------------------------------- plans

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

function renderDownloads() {
  const id = state.savedId;
  ui.downloads.hidden = id == null;
  for (const link of ui.downloads.querySelectorAll("a[data-format]")) {
    if (id == null) link.removeAttribute("href");
    else link.href = state.api.exportUrl(id, link.dataset.format);
  }
}

function removePlan() {
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

function showPlan(plan, { saved }) {
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
function fitMap(bounds) {
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
async function generate({ save = false, quiet = false } = {}) {
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
function replanIfPlanned() {
  if (!state.plan) return;
  clearTimeout(replanTimer);
  replanTimer = setTimeout(() => {
    if (state.plan) generate();
  }, REPLAN_DELAY_MS);
}

// ---------------------------------------------------------------- saved plans

async function openPlan(id, { quiet = false } = {}) {
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

async function deletePlan(id, title) {
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

// ---------------------------------------------------------------- import, start over

async function importField(file) {
  endPlacing();
  clearError();
  try {
    const seq = ++state.importSeq;
    setStatus(t("Reading {file}…", { file: file.name }), { sticky: true });
    // The server reads every import format (GeoJSON, KML/KMZ, zipped Shapefile, GeoPackage).
    const { fields, start, finish } = await parseFieldFile(state.parseUrl, file, postForm);
    closeFieldChooser();
    if (fields.length > 1) {
      setStatus(t("Choose one of the {count} fields of {file}.", { count: fields.length, file: file.name }), {
        sticky: true,
      });
    }
    const chosen =
      fields.length === 1
        ? fields[0]
        : await chooseField(state.map, fields, {
            anchor: ui.importField.closest("section"),
            fileName: file.name,
            fit: fitMap,
            importAll: () => importAllFields(file),
          });
    if (chosen == null) {
      if (seq === state.importSeq) setStatus(""); // cancelled, not replaced by a newer import
      return;
    }
    state.map.pm.disableDraw();
    const layer = fieldFromPolygon(chosen.geometry);
    placeMarker("start", start);
    placeMarker("finish", finish);
    const { interval_m: intervalM, name, id } = chosen.properties ?? {};
    if (intervalM != null && intervalM > 0) ui.interval.value = String(intervalM);
    const title = name || id;
    if (title && !ui.planName.value.trim()) ui.planName.value = title;
    saveDraft();
    const bounds = layer.getBounds();
    for (const marker of Object.values(state.markers)) if (marker) bounds.extend(marker.getLatLng());
    fitMap(bounds);
    setStatus(t("Imported {file}. Check the interval, then press Generate path.", { file: file.name }));
  } catch (error) {
    setStatus("");
    showFailure(error);
  }
}

/** Store every field of `file` in the organisation's registry (POST /api/fields/import). */
async function importAllFields(file) {
  clearError();
  const form = new FormData();
  form.append("file", file, file.name);
  try {
    const { created, reused } = await postForm(state.parseUrl.replace(/parse$/, "import"), form);
    setStatus(
      t("Added {created} fields of {file} to your fields ({reused} were there already).", {
        created,
        file: file.name,
        reused,
      }),
    );
    state.fields?.refresh();
  } catch (error) {
    showFailure(error);
  }
}

function startOver() {
  const drawn = state.field || state.markers.start || state.markers.finish;
  if (drawn && !window.confirm(t("Start over? The field, the start and the finish are removed from the map (saved plans stay)."))) {
    return;
  }
  closeFieldChooser();
  endPlacing();
  state.walker.end();
  clearError();
  state.map.pm.disableDraw();
  state.field?.remove();
  state.field = null;
  placeMarker("start", null);
  placeMarker("finish", null);
  removePlan();
  forget(KEYS.draft);
  setStatus("");
}

/** Put a field of the registry on the map, with its gates and name, ready to plan. */
function loadRegistryField(field) {
  endPlacing();
  clearError();
  state.map.pm.disableDraw();
  const layer = fieldFromPolygon(field.boundary);
  placeMarker("start", field.start);
  placeMarker("finish", field.finish);
  ui.planName.value = field.name;
  saveDraft();
  fitMap(layer.getBounds());
  setStatus(t("{name}: check the interval, then press Generate path.", { name: field.name }));
}

/**
 * Sign in (account.js); with no connection, go on without: the page and the draft work, and
 * signing in happens when the network is back (before waiting saves are sent).
 */
async function ensureSignedIn(apiUrl) {
  if (state.signedIn) return true;
  try {
    await signIn(apiUrl);
    state.signedIn = true;
  } catch (error) {
    if (!(error instanceof TypeError)) throw error; // TypeError: fetch could not reach the server
  }
  return state.signedIn;
}

// ---------------------------------------------------------------- wiring

function wireControls() {
  ui.panelToggle.addEventListener("click", () =>
    setPanelOpen(ui.panelToggle.getAttribute("aria-expanded") !== "true"),
  );
  ui.language.addEventListener("change", () => switchLanguage(ui.language.value));
  ui.drawField.addEventListener("click", startDrawing);
  ui.importField.addEventListener("click", () => ui.importFile.click());
  ui.importFile.addEventListener("change", () => {
    const [file] = ui.importFile.files;
    ui.importFile.value = ""; // choosing the same file again must fire `change` again
    if (file) importField(file);
  });
  ui.setStart.addEventListener("click", () => beginPlacing("start"));
  ui.setFinish.addEventListener("click", () => beginPlacing("finish"));
  ui.gotoForm.addEventListener("submit", (event) => {
    event.preventDefault();
    clearError();
    if (goToCoordinates(state.map, ui.goto.value)) {
      ui.goto.removeAttribute("aria-invalid");
      revealMapOnPhone();
      setStatus(t("The map is at {position}.", { position: ui.goto.value.trim() }));
    } else {
      showError(t("Go to coordinates: “{typed}” is not a position. Type latitude and longitude in degrees, for example -8.6264, 115.2981.", { typed: ui.goto.value.trim() }));
      ui.goto.setAttribute("aria-invalid", "true");
      ui.goto.focus();
    }
  });
  ui.clearAll.addEventListener("click", startOver);
  ui.generate.addEventListener("click", () => generate());
  ui.save.addEventListener("click", () => generate({ save: true }));
  for (const control of [ui.interval, ui.angle, ui.speed, ui.planName, ui.objective, ui.headland]) {
    control.addEventListener("change", saveDraft);
    control.addEventListener("input", saveDraft);
  }
  // Enter in any text box plans, as a form would.
  for (const control of [ui.interval, ui.angle, ui.speed]) {
    control.addEventListener("keydown", (event) => {
      if (event.key === "Enter") generate();
    });
  }
  ui.planName.addEventListener("keydown", (event) => {
    if (event.key === "Enter") generate({ save: true });
  });
  document.addEventListener("keydown", (event) => {
    if (event.key === "Escape") {
      endPlacing();
      state.map.pm.disableDraw();
    }
  });
  state.map.on("click", onMapClick);
}

async function main() {
  if (!window.L?.PM) {
    document.getElementById("alert").textContent = t("The map library is missing on the server (run `npm ci`, or `make run`, which does it).");
    return;
  }
  restoreLanguageChoice();
  const dataset = ui.app.dataset;
  registerServiceWorker(dataset.serviceWorkerUrl); // first, so the page opens offline next time
  await ensureSignedIn(dataset.apiUrl);
  state.api = new PlansApi(dataset.plansUrl);
  closeFieldChooser();
  state.parseUrl = `${dataset.apiUrl.replace(/\/+$/, "")}/fields/parse`;
  state.map = createMap(dataset, {
    setStatus,
    showError,
    onWalk: () => state.walker.begin(),
    onGoto: () => {
      setPanelOpen(true);
      ui.goto.scrollIntoView({ block: "center" });
      ui.goto.focus();
    },
  });
  state.walker = setUpWalkControls({
    map: state.map,
    beforeStart: () => {
      endPlacing();
      clearError();
      state.map.pm.disableDraw();
      revealMapOnPhone();
    },
    onField: (latlngs) => adoptField(L.polygon(latlngs, FIELD_STYLE).addTo(state.map), { replot: false }),
    showError,
    setStatus,
  });
  setUpGeoman(state.map, {
    onCreate: (layer) => {
      adoptField(layer, { replot: false });
      checkSelfIntersection(layer);
    },
    onDrawEnd: () => setStatus(""),
    onCut: (original, layer) => {
      if (original === state.field) adoptField(layer, { replot: true });
    },
    onRemove: (layer) => {
      if (layer === state.field) {
        state.field = null;
        removePlan();
        saveDraft();
      }
    },
  });
  state.checks = setUpChecks({
    map: state.map,
    api: new ChecksApi(dataset.apiUrl),
    setStatus,
    showFailure,
    clearError,
    onResult: showResultOnPhone,
    onPlanCreated: async (plan) => {
      await state.saved.refresh();
      await openPlan(plan.id);
    },
  });
  state.saved = setUpSavedPlans({
    api: state.api,
    onOpen: (id) => openPlan(id),
    onDelete: deletePlan,
    showFailure,
    currentId: () => state.savedId,
  });
  state.fields = setUpFields({
    map: state.map,
    apiUrl: dataset.apiUrl,
    loadField: loadRegistryField,
    onPlansChanged: () => state.saved.refresh(),
  });
  wireControls();
  setUpVehicle(dataset.apiUrl);
  setPanelOpen(false);
  restoreDraft();
  if (state.signedIn) state.saved.refresh();
  watchConnection({
    api: state.api,
    beforeFlush: () => ensureSignedIn(dataset.apiUrl),
    onConnectionChange: updateNotice,
    onFlushed: ({ sent, refused }) => {
      updateNotice();
      if (sent.length > 0) {
        setStatus(tn("{count} plan saved offline has been sent.", "{count} plans saved offline have been sent.", sent.length, { count: sent.length }));
      }
      if (refused.length > 0) showFailure(refused[0].error);
      state.saved.refresh();
      state.fields?.refresh();
    },
  });
  updateNotice();
  ui.app.dataset.ready = "true"; // tests wait for this before clicking the map
}

main();
