// The map itself: base layers (satellite, OpenStreetMap) with a notice when their pictures do
// not load, "Show my location", and Leaflet-Geoman's drawing tool in the page's language.
// The page (map.js) says what happens to what is drawn, through the hooks.

/* global L */

import { t, tapOrClick } from "./i18n.js";
import { formatNumber } from "./format.js";
import { KEYS, readStored, store } from "./storage.js";
import { locationProblem } from "./walk.js";

/** Ketewel, Gianyar, Bali: the paper's field trial, a sensible first view for the farmers we serve. */
const DEFAULT_VIEW = { lat: -8.6264, lng: 115.2981, zoom: 18 };
/** Tile errors with no tile loaded before the map says the pictures are missing. */
const TILE_ERRORS_BEFORE_NOTICE = 4;

export const FIELD_STYLE = { color: "#ffd54a", weight: 3, fillColor: "#ffd54a", fillOpacity: 0.12 };

const $ = (id) => document.getElementById(id);

function tileLayer(url, attribution, layerId) {
  // Tiles exist to zoom 19; a field of a few ares needs closer, so Leaflet scales them up.
  return L.tileLayer(url, { attribution, maxNativeZoom: 19, maxZoom: 22, layerId });
}

function baseLayers(dataset) {
  const layers = {};
  if (dataset.satelliteTileUrl) {
    layers[t("Satellite")] = tileLayer(
      dataset.satelliteTileUrl,
      "Imagery &copy; Esri, Maxar, Earthstar Geographics, and the GIS User Community",
      "Satellite",
    );
  }
  if (dataset.streetTileUrl) {
    layers.OpenStreetMap = tileLayer(
      dataset.streetTileUrl,
      '&copy; <a href="https://www.openstreetmap.org/copyright">OpenStreetMap</a> contributors',
      "OpenStreetMap",
    );
  }
  return layers;
}

/** Where the person last looked, so the map reopens on their own fields. */
function savedView() {
  const view = readStored(KEYS.view);
  const valid = ["lat", "lng", "zoom"].every((key) => Number.isFinite(view?.[key]));
  return valid ? view : DEFAULT_VIEW;
}

/** Say so when the map pictures do not load (no signal, no internet, a tile server down). */
function watchTiles(map, layers, hooks) {
  const notice = $("tile-notice");
  let errors = 0;
  let loaded = false;
  let dismissed = false;
  for (const layer of Object.values(layers)) {
    layer.on("tileload", () => {
      loaded = true;
      errors = 0;
      notice.hidden = true;
    });
    layer.on("tileerror", () => {
      errors += 1;
      if (!loaded && !dismissed && errors >= TILE_ERRORS_BEFORE_NOTICE) notice.hidden = false;
    });
  }
  map.on("baselayerchange", () => {
    loaded = false;
    errors = 0;
  });
  $("tile-dismiss").addEventListener("click", () => {
    dismissed = true;
    notice.hidden = true;
  });
  $("tile-goto").addEventListener("click", hooks.onGoto);
  $("tile-walk").addEventListener("click", hooks.onWalk);
}

/**
 * Make the map: zoom, base layers (remembered), the tile notice, "Show my location", scale.
 *
 * @param {DOMStringMap} dataset The page's data- attributes (tile URLs).
 * @param {{setStatus: Function, showError: Function, onGoto: Function, onWalk: Function}} hooks
 */
export function createMap(dataset, hooks) {
  const view = savedView();
  // Half zoom steps let a small field fill the screen when the map fits it.
  const map = L.map("map", { zoomControl: false, maxZoom: 22, minZoom: 2, zoomSnap: 0.5 }).setView(
    [view.lat, view.lng],
    view.zoom,
  );
  L.control.zoom({ zoomInTitle: t("Zoom in"), zoomOutTitle: t("Zoom out") }).addTo(map);
  const layers = baseLayers(dataset);
  const names = Object.keys(layers);
  if (names.length > 0) {
    // Remembered by a name that does not change with the language ("Satellite", "OpenStreetMap").
    const preferred = readStored(KEYS.baseLayer);
    const chosen = Object.values(layers).find((layer) => layer.options.layerId === preferred);
    (chosen ?? layers[names[0]]).addTo(map);
    L.control.layers(layers, null, { position: "topright" }).addTo(map);
    map.on("baselayerchange", (event) => store(KEYS.baseLayer, event.layer.options.layerId));
  }
  watchTiles(map, layers, hooks);
  addLocateControl(map, hooks);
  L.control.scale({ metric: true, imperial: false, position: "bottomright" }).addTo(map);
  map.attributionControl.setPrefix('<a href="https://leafletjs.com">Leaflet</a>');
  map.on("moveend", () => {
    const { lat, lng } = map.getCenter();
    store(KEYS.view, { lat, lng, zoom: map.getZoom() });
  });
  return map;
}

/** Zoom at which "Show my location" shows the person's surroundings: a few fields across. */
const LOCATE_ZOOM = 19;

/**
 * A map button that centres the map on the phone's GPS position: in the field, the quickest
 * way to find the field. Browsers allow it on HTTPS (and localhost) only.
 */
function addLocateControl(map, { setStatus, showError }) {
  const Locate = L.Control.extend({
    options: { position: "topright" },
    onAdd() {
      const button = L.DomUtil.create("button", "locate-button leaflet-bar");
      button.type = "button";
      button.title = t("Show my location");
      button.setAttribute("aria-label", t("Show my location"));
      L.DomEvent.disableClickPropagation(button);
      L.DomEvent.on(button, "click", () => {
        if (!window.isSecureContext) {
          showError(locationProblem(null));
          return;
        }
        setStatus(t("Finding your location…"), { sticky: true });
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
    const accuracy = t("{length} m", { length: formatNumber(Math.round(event.accuracy / 2)) });
    setStatus(t("You are here (± {accuracy}).", { accuracy }));
  });
  map.on("locationerror", (event) => {
    setStatus("");
    showError(locationProblem(event));
  });
}

/** Geoman's toolbar buttons carry their name only as a tooltip; give it to screen readers too. */
function nameToolbarButtons(map) {
  for (const container of map.getContainer().querySelectorAll(".leaflet-pm-toolbar .button-container")) {
    const button = container.querySelector("a[role='button'], .leaflet-buttons-control-button");
    if (button && container.title) button.setAttribute("aria-label", container.title);
  }
}

/**
 * The drawing tool's words: Geoman's own Indonesian (setLang("id")) under ours, which say what
 * a farmer does ("Tap the first corner") instead of "vertex" and "layer".
 */
function geomanWords() {
  return {
    tooltips: {
      firstVertex: tapOrClick(t("Tap the first corner of the field"), t("Click the first corner of the field")),
      continueLine: tapOrClick(t("Tap the next corner"), t("Click the next corner")),
      finishPoly: tapOrClick(t("Tap the first corner again to close the field"), t("Click the first corner again to close the field")),
      finishRect: tapOrClick(t("Tap the opposite corner"), t("Click the opposite corner")),
    },
    actions: {
      finish: t("Finish"),
      cancel: t("Cancel"),
      removeLastVertex: t("Remove the last corner"),
    },
    buttonTitles: {
      drawPolyButton: t("Draw the field"),
      drawRectButton: t("Draw a rectangular field"),
      editButton: t("Move corners"),
      dragButton: t("Move the whole field"),
      cutButton: t("Cut out a hole (pond, hut, tree)"),
      deleteButton: t("Remove the field"),
    },
  };
}

/**
 * Leaflet-Geoman for the field: polygon and rectangle, corners, moving, holes, removing.
 *
 * @param {L.Map} map
 * @param {{onCreate: Function, onCut: Function, onRemove: Function, onDrawEnd: Function}} hooks
 */
export function setUpGeoman(map, hooks) {
  const lang = document.documentElement.lang;
  map.pm.setLang("tillpath", geomanWords(), lang === "id" ? "id" : "en");
  map.pm.setGlobalOptions({
    // Crossing edges are allowed while drawing and refused with words when the field closes:
    // Geoman's own refusal silently dropped the corner that crossed, so a bow tie became a triangle.
    allowSelfIntersection: true,
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
    if (event.layer instanceof L.Polygon) hooks.onCreate(event.layer);
  });
  map.on("pm:drawend", hooks.onDrawEnd);
  map.on("pm:cut", (event) => hooks.onCut(event.originalLayer, event.layer));
  map.on("pm:remove", (event) => hooks.onRemove(event.layer));
}

