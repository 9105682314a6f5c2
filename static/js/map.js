// The map page: draw or import a field, place start and finish, ask the API for a path, show it,
// save it, download it. The page holds what the person drew and typed; the API does all the
// planning (style.md §4), so nothing here computes geometry beyond drawing it.

/* global L */

import { signIn } from "./account.js";
import { ApiError, ChecksApi, PlansApi, postForm } from "./api.js";
import { setUpChecks } from "./checks.js";
import { FieldFileError, polygonOf } from "./fieldfile.js";
import { chooseField, closeFieldChooser, parseFieldFile } from "./fieldpicker.js";
import {
  formatAngle,
  formatArea,
  formatDate,
  formatDuration,
  formatLength,
  formatPercent,
  friendlyError,
} from "./format.js";
import { setUpFields } from "./fields.js";
import { drawPlan } from "./planlayer.js";
import { fillVehicle, setUpVehicle, vehicleControls, vehicleRequest } from "./vehicle.js";

/** Ketewel, Gianyar, Bali: the paper's field trial, a sensible first view for the farmers we serve. */
const DEFAULT_VIEW = { lat: -8.6264, lng: 115.2981, zoom: 18 };
const VIEW_KEY = "tillpath.view";
const BASE_LAYER_KEY = "tillpath.baseLayer";
const DEFAULT_SPEED_MPS = 0.56;
/** Narrow screens get the map full-screen and the controls in a sheet (see app.css). */
const PHONE_QUERY = window.matchMedia("(max-width: 720px)");

const FIELD_STYLE = { color: "#ffd54a", weight: 3, fillColor: "#ffd54a", fillOpacity: 0.12 };

const $ = (id) => document.getElementById(id);

const ui = {
  app: $("app"),
  panel: $("panel"),
  panelToggle: $("panel-toggle"),
  alert: $("alert"),
  status: $("status"),
  drawField: $("draw-field"),
  importField: $("import-field"),
  importFile: $("import-file"),
  setStart: $("set-start"),
  setFinish: $("set-finish"),
  clearAll: $("clear-all"),
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
  savedPlans: $("saved-plans"),
  savedEmpty: $("saved-empty"),
};

/** Which form control shows each API input, to point at it when the API refuses it. */
const INPUT_CONTROLS = {
  name: ui.planName,
  interval_m: ui.interval,
  angle_deg: ui.angle,
  objective: ui.objective,
  headland_passes: ui.headland,
  speed_mps: ui.speed,
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
  parseUrl: null, // POST /api/fields/parse: the server's reader of field files
  importSeq: 0, // a newer import supersedes a field choice still open
};

// ---------------------------------------------------------------- messages

function setStatus(text) {
  ui.status.textContent = text;
}

function clearError() {
  ui.alert.textContent = "";
  for (const control of Object.values(INPUT_CONTROLS)) control.removeAttribute("aria-invalid");
}

/** Show a problem in the alert region and point at the control it concerns. */
function showError(message, input = null) {
  clearError();
  ui.alert.textContent = message;
  setPanelOpen(true); // on a phone the alert would otherwise hide behind the map
  const control = INPUT_CONTROLS[input] ?? vehicleControls()[input];
  if (control) {
    control.setAttribute("aria-invalid", "true");
    control.focus();
  }
}

function showFailure(error) {
  if (error instanceof ApiError) {
    const { message, input } = friendlyError(error.status, error.detail);
    showError(message, input);
  } else if (error instanceof FieldFileError) {
    showError(error.message);
  } else {
    console.error(error);
    showError(`Something went wrong in the page: ${error?.message ?? error}`);
  }
}

// ---------------------------------------------------------------- panel (phones)

function setPanelOpen(open) {
  ui.app.classList.toggle("panel-open", open);
  ui.panelToggle.setAttribute("aria-expanded", String(open));
}

/** On a phone, get the sheet out of the way when the next step is a tap on the map. */
function revealMapOnPhone() {
  if (PHONE_QUERY.matches) setPanelOpen(false);
}

// ---------------------------------------------------------------- the map

function tileLayer(url, attribution) {
  // Tiles exist to zoom 19; a field of a few ares needs closer, so Leaflet scales them up.
  return L.tileLayer(url, { attribution, maxNativeZoom: 19, maxZoom: 22 });
}

function baseLayers(dataset) {
  const layers = {};
  if (dataset.satelliteTileUrl) {
    layers.Satellite = tileLayer(
      dataset.satelliteTileUrl,
      "Imagery &copy; Esri, Maxar, Earthstar Geographics, and the GIS User Community",
    );
  }
  if (dataset.streetTileUrl) {
    layers.OpenStreetMap = tileLayer(
      dataset.streetTileUrl,
      '&copy; <a href="https://www.openstreetmap.org/copyright">OpenStreetMap</a> contributors',
    );
  }
  return layers;
}

/** localStorage, which private modes and locked-down browsers may refuse: then we forget. */
function readStored(key) {
  try {
    return JSON.parse(localStorage.getItem(key));
  } catch {
    return null;
  }
}

function store(key, value) {
  try {
    localStorage.setItem(key, JSON.stringify(value));
  } catch {
    // Remembering is a convenience only.
  }
}

/** Where the person last looked, so the map reopens on their own fields. */
function savedView() {
  const view = readStored(VIEW_KEY);
  const valid = ["lat", "lng", "zoom"].every((key) => Number.isFinite(view?.[key]));
  return valid ? view : DEFAULT_VIEW;
}

function createMap(dataset) {
  const view = savedView();
  // Half zoom steps let a small field fill the screen when the map fits it.
  const map = L.map("map", { zoomControl: true, maxZoom: 22, minZoom: 2, zoomSnap: 0.5 }).setView(
    [view.lat, view.lng],
    view.zoom,
  );
  const layers = baseLayers(dataset);
  const names = Object.keys(layers);
  if (names.length > 0) {
    const preferred = readStored(BASE_LAYER_KEY);
    layers[names.includes(preferred) ? preferred : names[0]].addTo(map);
    L.control.layers(layers, null, { position: "topright" }).addTo(map);
    map.on("baselayerchange", (event) => store(BASE_LAYER_KEY, event.name));
  }
  addLocateControl(map);
  L.control.scale({ metric: true, imperial: false, position: "bottomright" }).addTo(map);
  map.on("moveend", () => {
    const { lat, lng } = map.getCenter();
    store(VIEW_KEY, { lat, lng, zoom: map.getZoom() });
  });
  return map;
}

/** Zoom at which "Show my location" shows the person's surroundings: a few fields across. */
const LOCATE_ZOOM = 19;

/**
 * A map button that centres the map on the phone's GPS position: in the field, the quickest
 * way to find the field. Browsers allow it on HTTPS (and localhost) only.
 */
function addLocateControl(map) {
  const Locate = L.Control.extend({
    options: { position: "topright" },
    onAdd() {
      const button = L.DomUtil.create("button", "locate-button leaflet-bar");
      button.type = "button";
      button.title = "Show my location";
      button.setAttribute("aria-label", "Show my location");
      L.DomEvent.disableClickPropagation(button);
      L.DomEvent.on(button, "click", () => {
        setStatus("Finding your location…");
        map.locate({ setView: true, maxZoom: LOCATE_ZOOM, enableHighAccuracy: true, timeout: 15000 });
      });
      return button;
    },
  });
  new Locate().addTo(map);
  let here = null;
  map.on("locationfound", (event) => {
    here?.remove();
    here = L.circle(event.latlng, {
      radius: event.accuracy / 2,
      color: "#2f7de1",
      weight: 2,
      fillOpacity: 0.15,
      interactive: false,
      pmIgnore: true,
    }).addTo(map);
    setStatus(`You are here (± ${Math.round(event.accuracy / 2)} m).`);
  });
  map.on("locationerror", (event) => {
    setStatus("");
    showError(`Cannot find your location: ${event.message}. Allow location access, or find the field on the map.`);
  });
}

/** Geoman's toolbar buttons carry their name only as a tooltip; give it to screen readers too. */
function nameToolbarButtons(map) {
  for (const container of map.getContainer().querySelectorAll(".leaflet-pm-toolbar .button-container")) {
    const button = container.querySelector("a[role='button'], .leaflet-buttons-control-button");
    if (button && container.title) button.setAttribute("aria-label", container.title);
  }
}

function setUpGeoman(map) {
  map.pm.setGlobalOptions({
    allowSelfIntersection: false, // a boundary that crosses itself cannot be planned
    snappable: true,
    pathOptions: FIELD_STYLE,
    templineStyle: { color: FIELD_STYLE.color },
    hintlineStyle: { color: FIELD_STYLE.color, dashArray: "5 5" },
  });
  // Only what a field needs: polygon and rectangle, editing corners, moving, cutting holes
  // (ponds, huts, trees) and removing.
  map.pm.addControls({
    position: "topleft",
    drawMarker: false,
    drawCircleMarker: false,
    drawPolyline: false,
    drawCircle: false,
    drawText: false,
    rotateMode: false,
  });
  nameToolbarButtons(map);
  map.on("pm:create", (event) => {
    if (event.layer instanceof L.Polygon) adoptField(event.layer, { replot: false });
  });
  map.on("pm:drawend", () => setStatus(""));
  map.on("pm:cut", (event) => {
    if (event.originalLayer === state.field) adoptField(event.layer, { replot: true });
  });
  map.on("pm:remove", (event) => {
    if (event.layer === state.field) {
      state.field = null;
      removePlan();
    }
  });
}

// ---------------------------------------------------------------- field, start, finish

/** Make `layer` the field (one at a time), following its edits. */
function adoptField(layer, { replot }) {
  if (state.field && state.field !== layer) state.field.remove();
  state.field = layer;
  layer.setStyle(FIELD_STYLE);
  layer.on("pm:edit pm:dragend", () => replanIfPlanned());
  if (replot) replanIfPlanned();
  else removePlan();
}

function fieldFromPolygon(polygon) {
  const layer = L.polygon(L.GeoJSON.coordsToLatLngs(polygon.coordinates, 1), FIELD_STYLE);
  layer.addTo(state.map);
  adoptField(layer, { replot: false });
  return layer;
}

/** The field as a GeoJSON Polygon, full precision; null (with an alert) when there is none. */
function fieldGeometry() {
  if (!state.field) {
    showError("Field: there is no field yet. Press Draw field and click its corners on the map, or use Import field.");
    return null;
  }
  const geometry = state.field.toGeoJSON(false).geometry;
  if (geometry.type === "MultiPolygon") {
    if (geometry.coordinates.length === 1) return { type: "Polygon", coordinates: geometry.coordinates[0] };
    showError("Field: the cut split the field into separate pieces. Plan one piece at a time: remove the others.");
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
  const title = role === "start" ? "Start (drag to move)" : "Finish (drag to move)";
  const marker = L.marker(latlng, {
    icon: endpointIcon(role),
    draggable: true,
    pmIgnore: true, // dragging is ours; Geoman's edit modes leave these alone
    title,
    zIndexOffset: 1000,
  }).addTo(state.map);
  // The pin's letter would be its accessible name; the title says what it is and what to do.
  marker.getElement()?.setAttribute("aria-label", title);
  marker.on("dragend", () => replanIfPlanned());
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
  setStatus(role === "start" ? "Tap the map where the tractor starts." : "Tap the map where the tractor must finish.");
  revealMapOnPhone();
}

function endPlacing() {
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
  replanIfPlanned();
}

function startDrawing() {
  endPlacing();
  clearError();
  state.map.pm.enableDraw("Polygon", { finishOn: null });
  setStatus("Click the corners of the field. Click the first corner again to close it.");
  revealMapOnPhone();
}

// ---------------------------------------------------------------- the form

/** A decimal typed with a point or a comma; NaN when it is not a number, null when empty. */
function parseDecimal(text) {
  const cleaned = text.trim().replace(",", ".");
  if (cleaned === "") return null;
  return /^[-+]?(\d+\.?\d*|\.\d+)$/.test(cleaned) ? Number(cleaned) : Number.NaN;
}

function numberInput(control, label, { required = false, fallback = null } = {}) {
  const value = parseDecimal(control.value);
  if (value === null && !required) return { value: fallback };
  if (value === null || Number.isNaN(value)) {
    const typed = control.value.trim();
    const why = typed ? `“${typed}” is not a number` : "this is empty";
    return { error: `${label}: ${why}. Type a number, for example ${control.placeholder.replace("e.g. ", "") || 4}.` };
  }
  return { value };
}

/** The request body of product.md §3 from the page; null (with an alert) when incomplete. */
function buildRequest() {
  const field = fieldGeometry();
  if (!field) return null;
  const inputs = {
    interval_m: numberInput(ui.interval, "Interval (m)", { required: true }),
    angle_deg: numberInput(ui.angle, "Line angle (°)"),
    speed_mps: numberInput(ui.speed, "Speed (m/s)", { fallback: DEFAULT_SPEED_MPS }),
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

function fillForm(request, name) {
  ui.interval.value = request.interval_m ?? "";
  ui.angle.value = request.angle_deg ?? "";
  ui.objective.value = request.objective ?? "shortest_path";
  ui.headland.value = String(request.headland_passes ?? 0);
  ui.speed.value = request.speed_mps ?? DEFAULT_SPEED_MPS;
  ui.planName.value = name ?? request.name ?? "";
  fillVehicle(request);
}

// ---------------------------------------------------------------- plans

function planTitle(plan) {
  return plan.name || `Plan ${plan.id}`;
}

function renderSummary(stats) {
  const figures = {
    lines: String(stats.line_count),
    waypoints: String(stats.waypoint_count),
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
  markCurrentSavedPlan();
  state.checks?.planChanged(null);
}

function showPlan(plan, { saved }) {
  state.planDrawing?.remove();
  state.plan = plan;
  state.savedId = saved ? plan.id : null;
  state.planDrawing = drawPlan(state.map, plan.geojson);
  renderSummary(plan.stats);
  renderDownloads();
  markCurrentSavedPlan();
  state.checks?.planChanged(state.savedId);
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

/** Ask the API for a plan from the page's inputs; `save` stores it too. */
async function generate({ save = false } = {}) {
  endPlacing();
  clearError();
  const request = buildRequest();
  if (!request) return;
  state.requestSeq += 1;
  const seq = state.requestSeq;
  setBusy(true);
  setStatus(save ? "Saving the plan…" : "Planning the path…");
  try {
    const plan = save ? await state.api.create(request) : await state.api.preview(request);
    if (seq !== state.requestSeq) return; // a newer request (a marker dragged again) wins
    showPlan(plan, { saved: save });
    const lines = `${plan.stats.line_count} line${plan.stats.line_count === 1 ? "" : "s"}`;
    setStatus(save ? `Saved “${planTitle(plan)}”.` : `Path ready: ${lines}.`);
    if (save) await refreshSavedPlans();
  } catch (error) {
    if (seq === state.requestSeq) {
      setStatus("");
      // What is drawn must match what was asked, or be nothing: a path for the old start or
      // the old boundary beside an error would mislead.
      removePlan();
      showFailure(error);
    }
  } finally {
    if (seq === state.requestSeq) setBusy(false);
  }
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

function markCurrentSavedPlan() {
  for (const item of ui.savedPlans.children) {
    const current = state.savedId != null && item.dataset.id === String(state.savedId);
    item.classList.toggle("current", current);
    if (current) item.setAttribute("aria-current", "true");
    else item.removeAttribute("aria-current");
  }
}

function savedPlanItem(plan) {
  const title = planTitle(plan);
  const item = document.createElement("li");
  item.dataset.id = String(plan.id);

  const open = document.createElement("button");
  open.type = "button";
  open.className = "open-plan";
  open.setAttribute("aria-label", `Open ${title}`);
  const name = document.createElement("span");
  name.className = "plan-name";
  name.textContent = title;
  const meta = document.createElement("span");
  meta.className = "plan-meta";
  const stats = plan.stats ?? {};
  meta.textContent = [formatDate(plan.created_at), `${stats.line_count} lines`, formatArea(stats.area_m2)]
    .filter(Boolean)
    .join(" · ");
  open.append(name, meta);
  open.addEventListener("click", () => openPlan(plan.id));

  const remove = document.createElement("button");
  remove.type = "button";
  remove.className = "delete-plan quiet";
  remove.textContent = "Delete";
  remove.setAttribute("aria-label", `Delete ${title}`);
  remove.addEventListener("click", () => deletePlan(plan.id, title));

  item.append(open, remove);
  return item;
}

async function refreshSavedPlans() {
  try {
    const { items, total } = await state.api.list({ limit: 50 });
    ui.savedPlans.replaceChildren(...items.map(savedPlanItem));
    ui.savedEmpty.hidden = items.length > 0;
    ui.savedEmpty.textContent = "No saved plans yet.";
    if (total > items.length) {
      ui.savedEmpty.hidden = false;
      ui.savedEmpty.textContent = `Showing the newest ${items.length} of ${total} plans.`;
    }
    markCurrentSavedPlan();
    state.fields?.refresh(); // a saved plan may have added a field to the registry
  } catch (error) {
    showFailure(error);
  }
}

async function openPlan(id) {
  endPlacing();
  clearError();
  try {
    const plan = await state.api.read(id);
    const request = plan.request ?? {};
    fillForm(request, plan.name);
    fieldFromPolygon(polygonOf(request.field));
    placeMarker("start", request.start);
    placeMarker("finish", request.finish);
    showPlan(plan, { saved: true });
    fitMap(state.planDrawing.bounds ?? state.field.getBounds());
    setStatus(`Opened “${planTitle(plan)}”.`);
  } catch (error) {
    showFailure(error);
  }
}

async function deletePlan(id, title) {
  if (!window.confirm(`Delete the plan “${title}”? This cannot be undone.`)) return;
  clearError();
  try {
    await state.api.remove(id);
    if (state.savedId === id) {
      // The path stays on the map, but it is no longer stored: nothing left to download.
      state.savedId = null;
      renderDownloads();
      state.checks?.planChanged(null);
    }
    setStatus(`Deleted “${title}”.`);
  } catch (error) {
    if (!(error instanceof ApiError && error.status === 404)) showFailure(error);
  }
  await refreshSavedPlans();
}

// ---------------------------------------------------------------- import, start over

async function importField(file) {
  endPlacing();
  clearError();
  try {
    const seq = ++state.importSeq;
    setStatus(`Reading ${file.name}…`);
    // The server reads every import format (GeoJSON, KML/KMZ, zipped Shapefile, GeoPackage).
    const { fields, start, finish } = await parseFieldFile(state.parseUrl, file, postForm);
    closeFieldChooser();
    if (fields.length > 1) setStatus(`Choose one of the ${fields.length} fields of ${file.name}.`);
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
    const bounds = layer.getBounds();
    for (const marker of Object.values(state.markers)) if (marker) bounds.extend(marker.getLatLng());
    fitMap(bounds);
    setStatus(`Imported ${file.name}. Check the interval, then press Generate path.`);
  } catch (error) {
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
    setStatus(`Added ${created} fields of ${file.name} to your fields (${reused} were there already).`);
    state.fields?.refresh();
  } catch (error) {
    showFailure(error);
  }
}

function startOver() {
  closeFieldChooser();
  endPlacing();
  clearError();
  state.map.pm.disableDraw();
  state.field?.remove();
  state.field = null;
  placeMarker("start", null);
  placeMarker("finish", null);
  removePlan();
  setStatus("");
}

// ---------------------------------------------------------------- wiring

function wireControls() {
  ui.panelToggle.addEventListener("click", () =>
    setPanelOpen(ui.panelToggle.getAttribute("aria-expanded") !== "true"),
  );
  ui.drawField.addEventListener("click", startDrawing);
  ui.importField.addEventListener("click", () => ui.importFile.click());
  ui.importFile.addEventListener("change", () => {
    const [file] = ui.importFile.files;
    ui.importFile.value = ""; // choosing the same file again must fire `change` again
    if (file) importField(file);
  });
  ui.setStart.addEventListener("click", () => beginPlacing("start"));
  ui.setFinish.addEventListener("click", () => beginPlacing("finish"));
  ui.clearAll.addEventListener("click", startOver);
  ui.generate.addEventListener("click", () => generate());
  ui.save.addEventListener("click", () => generate({ save: true }));
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

/** Put a field of the registry on the map, with its gates and name, ready to plan. */
function loadRegistryField(field) {
  endPlacing();
  clearError();
  state.map.pm.disableDraw();
  const layer = fieldFromPolygon(field.boundary);
  placeMarker("start", field.start);
  placeMarker("finish", field.finish);
  ui.planName.value = field.name;
  fitMap(layer.getBounds());
  setStatus(`${field.name}: check the interval, then press Generate path.`);
}

async function main() {
  if (!window.L?.PM) {
    ui.alert.textContent =
      "The map library is missing on the server (run `npm ci`, or `make run`, which does it).";
    return;
  }
  const dataset = ui.app.dataset;
  await signIn(dataset.apiUrl);
  state.api = new PlansApi(dataset.plansUrl);
  state.parseUrl = `${dataset.apiUrl.replace(/\/+$/, "")}/fields/parse`;
  state.map = createMap(dataset);
  setUpGeoman(state.map);
  state.checks = setUpChecks({
    map: state.map,
    api: new ChecksApi(dataset.apiUrl),
    setStatus,
    showFailure,
    clearError,
  });
  state.fields = setUpFields({
    map: state.map,
    apiUrl: dataset.apiUrl,
    loadField: loadRegistryField,
    onPlansChanged: () => refreshSavedPlans(),
  });
  wireControls();
  setUpVehicle(dataset.apiUrl);
  setPanelOpen(false);
  refreshSavedPlans();
  ui.app.dataset.ready = "true"; // tests wait for this before clicking the map
}

main();
