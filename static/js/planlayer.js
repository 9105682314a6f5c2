// Drawing a plan's GeoJSON (product.md §4) on the map. Everything drawn here comes from the API;
// the only arithmetic is screen placement of the direction arrows.

/* global L */

import { t } from "./i18n.js";

/** What each waypoint is, in words. */
const ROLE_LABELS = {
  start: t("start"),
  line_start: t("start of a line"),
  line_end: t("end of a line"),
  turn: t("turn"),
  headland: t("headland"),
  finish: t("finish"),
};

/** Line styles per feature kind; bright colours so they read on satellite imagery. */
const STYLES = {
  cell: { color: "#ffffff", weight: 1, dashArray: "4 4", opacity: 0.5, fillColor: "#ffffff", fillOpacity: 0.08 },
  line: { color: "#ffe14d", weight: 4, opacity: 0.95 },
  turn: { color: "#4dd8f0", weight: 3, opacity: 0.95 },
  headland: { color: "#ff9f43", weight: 4, opacity: 0.95 },
  round: { color: "#ff9f43", weight: 4, opacity: 0.95 }, // a spiral's rounds: passes round the field
  transit: { color: "#ffffff", weight: 3, opacity: 0.95, dashArray: "6 6" },
};

/** A dark casing under the whole route keeps the coloured lines visible on bright ground. */
const PATH_CASING = { color: "#14241a", weight: 8, opacity: 0.55, lineCap: "round", lineJoin: "round" };

/** Screen distance between direction arrows along the path [px]. */
const ARROW_SPACING_PX = 110;
/** Segments shorter than this on screen get no arrow: it would hide the waypoints [px]. */
const ARROW_MIN_SEGMENT_PX = 36;
/** Above this many waypoints, numbers would only clutter the map: show dots instead. */
const MAX_NUMBERED_WAYPOINTS = 400;

const kindOf = (feature) => feature?.properties?.kind;

/** The route as one LineString: the `path` feature, in order. */
function routeCoordinates(geojson) {
  const path = (geojson?.features ?? []).find(
    (f) => kindOf(f) === "path" && f.geometry?.type === "LineString",
  );
  return path ? path.geometry.coordinates : [];
}

function waypointIcon(props) {
  const role = props.role ?? "turn";
  return L.divIcon({
    className: `waypoint waypoint-${role}`,
    html: `<span>${Number(props.seq)}</span>`,
    iconSize: [22, 22],
    iconAnchor: [11, 11],
  });
}

/** "Waypoint 3: end of a line, line 0". Line numbers are the exports' (GPX, CSV), from 0. */
function waypointTooltip(props) {
  const role = ROLE_LABELS[props.role] ?? String(props.role ?? "");
  const seq = String(Number(props.seq));
  if (props.line == null) return t("Waypoint {seq}: {role}", { seq, role });
  return t("Waypoint {seq}: {role}, line {line}", { seq, role, line: String(Number(props.line)) });
}

function waypointLayer(geojson) {
  // Start and finish have their own draggable pins; a number under a pin would only peek out.
  // Turn waypoints are the driven curve, every half metre: the turn's line shows them.
  const points = (geojson?.features ?? []).filter(
    (f) => kindOf(f) === "waypoint" && !["start", "finish", "turn"].includes(f.properties?.role),
  );
  const numbered = points.length <= MAX_NUMBERED_WAYPOINTS;
  // Thousands of dots draw fast on one canvas and slowly as thousands of SVG elements.
  const canvas = numbered ? null : L.canvas({ padding: 0.5 });
  const layer = L.geoJSON(points, {
    pmIgnore: true,
    pointToLayer: (feature, latlng) =>
      numbered
        ? L.marker(latlng, { icon: waypointIcon(feature.properties ?? {}), pmIgnore: true, keyboard: false })
        : L.circleMarker(latlng, { renderer: canvas, radius: 3, color: "#14241a", weight: 1, fillColor: "#fff", fillOpacity: 1, pmIgnore: true }),
    onEachFeature: (feature, marker) => marker.bindTooltip(waypointTooltip(feature.properties ?? {})),
  });
  return { layer, renderer: canvas };
}

/**
 * An arrow pointing `degrees` clockwise from screen east. The rotation is set through the DOM
 * (CSSOM), not as a style="" attribute in the icon's HTML: the Content-Security-Policy
 * (style-src 'self') drops inline style attributes, and every arrow then pointed east.
 */
function arrowMarker(latlng, degrees) {
  const arrow = document.createElement("span");
  arrow.style.transform = `rotate(${degrees.toFixed(1)}deg)`;
  return L.marker(latlng, {
    icon: L.divIcon({ className: "path-arrow", html: arrow, iconSize: [18, 18], iconAnchor: [9, 9] }),
    interactive: false,
    keyboard: false,
    pmIgnore: true,
  });
}

/** Side of the screen patch that holds at most one arrow [px]. */
const ARROW_PATCH_PX = 22;
/** More arrows than this and the page slows down on a phone; the view never needs them all. */
const MAX_ARROWS = 500;

/** Arrows along each segment of the route in view, pointing the way the tractor drives. */
function addArrows(map, group, coordinates) {
  group.clearLayers();
  const view = map.getPixelBounds().pad(0.25); // a margin, so panning a little shows arrows
  const origin = map.getPixelOrigin();
  const taken = new Set();
  let added = 0;
  for (let i = 1; i < coordinates.length && added < MAX_ARROWS; i += 1) {
    // Rotation is a screen direction, so it comes from screen points, not from a bearing.
    const pa = map.latLngToLayerPoint(L.latLng(coordinates[i - 1][1], coordinates[i - 1][0]));
    const pb = map.latLngToLayerPoint(L.latLng(coordinates[i][1], coordinates[i][0]));
    const length = pa.distanceTo(pb);
    if (length < ARROW_MIN_SEGMENT_PX) continue;
    const degrees = (Math.atan2(pb.y - pa.y, pb.x - pa.x) * 180) / Math.PI;
    const count = Math.max(1, Math.floor(length / ARROW_SPACING_PX));
    for (let k = 0; k < count && added < MAX_ARROWS; k += 1) {
      const t = (k + 0.5) / count;
      const point = L.point(pa.x + (pb.x - pa.x) * t, pa.y + (pb.y - pa.y) * t);
      if (!view.contains(point.add(origin))) continue;
      // One arrow per patch of screen: where lines run closer than the arrows are wide (a big
      // field zoomed out), the first arrow in a patch speaks for its neighbours.
      const patch = `${Math.floor(point.x / ARROW_PATCH_PX)},${Math.floor(point.y / ARROW_PATCH_PX)}`;
      if (taken.has(patch)) continue;
      taken.add(patch);
      group.addLayer(arrowMarker(map.layerPointToLatLng(point), degrees));
      added += 1;
    }
  }
}

/** Typical short gap between consecutive waypoints on screen: the 25th percentile, because
 * half the gaps are long tillage lines and the other half short turns, where labels collide [px]. */
function typicalSpacing(map, points) {
  const gaps = [];
  for (let i = 1; i < points.length; i += 1) {
    gaps.push(map.latLngToLayerPoint(points[i - 1]).distanceTo(map.latLngToLayerPoint(points[i])));
  }
  gaps.sort((a, b) => a - b);
  return gaps.length ? gaps[Math.floor(gaps.length / 4)] : Infinity;
}

/** Waypoint numbers closer than this overlap into a smudge: then they shrink to dots [px]. */
const MIN_LABEL_SPACING_PX = 26;

/**
 * Draw a plan on `map` and return a handle to take it off again.
 *
 * @param {L.Map} map The map.
 * @param {object} geojson The plan's FeatureCollection (kinds: cell, line, turn, headland,
 *     round, transit, path, waypoint; the field is drawn by the page's own editable layer).
 * @returns {{bounds: L.LatLngBounds|null, remove: function(): void}}
 */
export function drawPlan(map, geojson) {
  const features = geojson?.features ?? [];
  const group = L.layerGroup([], { pmIgnore: true });
  const shown = (kinds) => features.filter((f) => kinds.includes(kindOf(f)));

  group.addLayer(L.geoJSON(shown(["cell"]), { pmIgnore: true, interactive: false, style: () => STYLES.cell }));
  const route = routeCoordinates(geojson);
  if (route.length > 1) {
    group.addLayer(L.polyline(route.map(([lon, lat]) => [lat, lon]), { ...PATH_CASING, interactive: false, pmIgnore: true }));
  }
  group.addLayer(
    L.geoJSON(shown(["headland", "round", "transit", "turn", "line"]), {
      pmIgnore: true,
      interactive: false,
      style: (feature) => STYLES[kindOf(feature)],
    }),
  );
  // Without per-kind features (an older or slimmer answer), the route alone still shows the way.
  if (shown(["line"]).length === 0 && route.length > 1) {
    group.addLayer(L.polyline(route.map(([lon, lat]) => [lat, lon]), { ...STYLES.line, interactive: false, pmIgnore: true }));
  }
  const arrows = L.layerGroup([], { pmIgnore: true });
  group.addLayer(arrows);
  const waypoints = waypointLayer(geojson);
  group.addLayer(waypoints.layer);
  group.addTo(map);

  const waypointLatLngs = features
    .filter((f) => kindOf(f) === "waypoint" && f.geometry?.type === "Point")
    .map((f) => L.latLng(f.geometry.coordinates[1], f.geometry.coordinates[0]));
  const redraw = () => {
    addArrows(map, arrows, route);
    const crowded = typicalSpacing(map, waypointLatLngs) < MIN_LABEL_SPACING_PX;
    map.getContainer().classList.toggle("waypoints-crowded", crowded);
  };
  redraw();
  map.on("zoomend moveend", redraw);

  const everything = L.geoJSON(features.filter((f) => f.geometry));
  const bounds = everything.getBounds();
  return {
    bounds: bounds.isValid() ? bounds : null,
    remove() {
      map.off("zoomend moveend", redraw);
      map.getContainer().classList.remove("waypoints-crowded");
      group.remove();
      waypoints.renderer?.remove(); // a renderer outlives its layers unless removed itself
    },
  };
}
