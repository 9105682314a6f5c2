// The field, the start and the finish on the map: drawing, editing and placing them.

/* global L */

import { FIELD_STYLE } from "./basemap.js";
import { saveDraft } from "./draft.js";
import { t, tapOrClick } from "./i18n.js";
import { clearError, revealMapOnPhone, setStatus, showError } from "./messages.js";
import { state, ui } from "./pagestate.js";
import { removePlan, replanIfPlanned } from "./planview.js";

/** A boundary whose edges cross (a bow tie) cannot be tilled as one field: say so at once. */
export function checkSelfIntersection(layer) {
  if (layer.pm?.hasSelfIntersection?.()) {
    showError(
      t("Field: the boundary crosses itself (like a bow tie). Move the corners so that no edges cross, or draw the field again."),
    );
    return true;
  }
  return false;
}

/** Make `layer` the field (one at a time), following its edits. */
export function adoptField(layer, { replot }) {
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

export function fieldFromPolygon(polygon) {
  const layer = L.polygon(L.GeoJSON.coordsToLatLngs(polygon.coordinates, 1), FIELD_STYLE);
  layer.addTo(state.map);
  adoptField(layer, { replot: false });
  return layer;
}

/** The field as a GeoJSON Polygon, full precision; null (with an alert) when there is none. */
export function fieldGeometry({ quiet = false } = {}) {
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
export function placeMarker(role, position) {
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

export function markerLonLat(role) {
  const marker = state.markers[role];
  if (!marker) return null;
  const { lat, lng } = marker.getLatLng();
  return [lng, lat];
}

export function beginPlacing(role) {
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

export function endPlacing() {
  if (!state.placing) return;
  state.placing = null;
  ui.app.classList.remove("placing");
  ui.setStart.setAttribute("aria-pressed", "false");
  ui.setFinish.setAttribute("aria-pressed", "false");
  setStatus("");
}

export function onMapClick(event) {
  if (!state.placing) return;
  const role = state.placing;
  endPlacing();
  placeMarker(role, event.latlng);
  saveDraft();
  replanIfPlanned();
}

export function startDrawing() {
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
