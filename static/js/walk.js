// Finding and outlining a field without map pictures: "Go to coordinates" (typed or pasted
// from a GPS or a map app) and "Walk the boundary" (the phone's GPS positions, recorded as the
// farmer walks the bund, become the field's corners, each with its accuracy).

/* global L */

import { formatMetres } from "./format.js";
import { t } from "./i18n.js";

/** A new point is recorded once the phone has moved this far from the last one [m]. */
export const WALK_MIN_STEP_M = 3;
/** Positions less accurate than this are shown but not recorded [m]. */
export const WALK_MAX_ACCURACY_M = 30;
/** Zoom that shows a field and its neighbours when going to coordinates. */
const GOTO_ZOOM = 19;

const WALK_STYLE = { color: "#ffd54a", weight: 3, dashArray: "6 6" };

/**
 * Read "lat, lon" as typed: decimal degrees with a point or a comma, N/S/E/W letters allowed
 * ("8.6264 S 115.2981 E"), or a map app's "-8.6264,115.2981".
 *
 * @returns {{lat: number, lng: number}|null} null when the text is not a position.
 */
export function parseCoordinates(text) {
  const cleaned = text.trim().toUpperCase().replace(/°/g, " ").replace(/\s+/g, " ");
  let parts;
  if (cleaned.includes(";")) parts = cleaned.split(";");
  else if (cleaned.includes(", ")) parts = cleaned.split(", ");
  else if ((cleaned.match(/,/g) ?? []).length === 1) parts = cleaned.split(",");
  else parts = cleaned.split(/ (?=[-+]?\d)/);
  if (parts.length !== 2) return null;
  // Hemispheres in English and Indonesian: LU/LS (lintang utara/selatan), BT/BB (bujur timur/barat).
  const part = /^([-+]?\d+(?:[.,]\d+)?) ?(N|S|E|W|LU|LS|BT|BB)?$/;
  const [latMatch, lngMatch] = parts.map((p) => part.exec(p.trim()));
  if (!latMatch || !lngMatch) return null;
  const value = (match, negative) => {
    const n = Number(match[1].replace(",", "."));
    return negative.includes(match[2]) ? -Math.abs(n) : n;
  };
  const lat = value(latMatch, ["S", "LS"]);
  const lng = value(lngMatch, ["W", "BB"]);
  if (!(Math.abs(lat) <= 90 && Math.abs(lng) <= 180)) return null;
  return { lat, lng };
}

/** Centre `map` on typed coordinates; returns false (nothing moved) when they are not valid. */
export function goToCoordinates(map, text) {
  const position = parseCoordinates(text);
  if (!position) return false;
  map.setView([position.lat, position.lng], Math.max(map.getZoom(), GOTO_ZOOM), { animate: false });
  return true;
}

/** Why the phone's position cannot be had, in words that say what to do. */
export function locationProblem(error) {
  if (!window.isSecureContext) {
    return t(
      "The phone's GPS works only when the page is opened over HTTPS (or on this computer as localhost). Ask the person who runs tillpath to start it with HTTPS (tillpath serve --certfile --keyfile) and open the https:// address.",
    );
  }
  if (error?.code === 1) {
    return t("The browser may not use your location. Allow location for this page in the browser's settings, or find the field on the map.");
  }
  if (error?.code === 3) return t("The GPS found no position in time. Go outside, away from trees and roofs, and try again.");
  return t("Cannot find your location ({reason}). Find the field on the map instead.", { reason: error?.message ?? "?" });
}

/**
 * Record the phone's positions along the bund.
 *
 * @param {object} options
 * @param {L.Map} options.map
 * @param {(text: string) => void} options.onStatus What the walk bar says.
 * @param {(latlngs: L.LatLng[], accuracies: number[]) => void} options.onFinish The walked field.
 * @param {(message: string) => void} options.onError
 * @returns {{addPoint: () => void, finish: () => void, cancel: () => void}}
 */
export function startWalk({ map, onStatus, onFinish, onError }) {
  const points = []; // {latlng, accuracy}
  let last = null; // the newest position, recorded or not
  const trace = L.polyline([], { ...WALK_STYLE, pmIgnore: true, interactive: false }).addTo(map);
  const here = L.circle([0, 0], { radius: 1, color: "#2f7de1", weight: 2, fillOpacity: 0.15, interactive: false, pmIgnore: true });
  let watch = null;

  function say() {
    const accuracy = last ? formatMetres(last.accuracy) : "–";
    onStatus(
      points.length === 0
        ? t("Walk to a corner of the field. GPS accuracy: ± {accuracy}.", { accuracy })
        : t("{count} points recorded; keep walking along the bund. GPS accuracy: ± {accuracy}.", { count: points.length, accuracy }),
    );
  }

  function record(position) {
    points.push(position);
    trace.setLatLngs(points.map((p) => p.latlng));
    say();
  }

  function onPosition(event) {
    const latlng = L.latLng(event.coords.latitude, event.coords.longitude);
    last = { latlng, accuracy: event.coords.accuracy };
    here.setLatLng(latlng).setRadius(event.coords.accuracy);
    if (!map.hasLayer(here)) here.addTo(map);
    if (points.length === 0) map.setView(latlng, Math.max(map.getZoom(), GOTO_ZOOM), { animate: false });
    const far = points.length === 0 || points.at(-1).latlng.distanceTo(latlng) >= WALK_MIN_STEP_M;
    if (far && event.coords.accuracy <= WALK_MAX_ACCURACY_M) record(last);
    else say();
  }

  function stop() {
    if (watch != null) navigator.geolocation.clearWatch(watch);
    watch = null;
    trace.remove();
    here.remove();
  }

  if (!window.isSecureContext || !navigator.geolocation) {
    queueMicrotask(() => onError(locationProblem(null)));
  } else {
    watch = navigator.geolocation.watchPosition(onPosition, (error) => onError(locationProblem(error)), {
      enableHighAccuracy: true,
      maximumAge: 0,
      timeout: 30_000,
    });
    say();
  }

  return {
    /** Record where the phone is now, even if it has not moved far (a corner). */
    addPoint() {
      if (last) record(last);
    },
    finish() {
      if (points.length < 3) {
        onError(t("Walk the boundary: at least three points are needed for a field; {count} recorded so far.", { count: points.length }));
        return false;
      }
      stop();
      onFinish(points.map((p) => p.latlng), points.map((p) => p.accuracy));
      return true;
    },
    cancel: stop,
  };
}

/**
 * Wire the Walk the boundary button and the walk bar over the map.
 *
 * @param {object} options
 * @param {L.Map} options.map
 * @param {() => void} options.beforeStart Stop whatever else the page was doing.
 * @param {(latlngs: L.LatLng[]) => void} options.onField The walked boundary becomes the field.
 * @param {(message: string) => void} options.showError
 * @param {(text: string) => void} options.setStatus
 * @returns {{begin: () => void, end: () => void}}
 */
export function setUpWalkControls({ map, beforeStart, onField, showError, setStatus }) {
  const $ = (id) => document.getElementById(id);
  const ui = { button: $("walk-boundary"), bar: $("walk-bar"), status: $("walk-status"), notice: $("tile-notice") };
  let walk = null;

  function end() {
    walk?.cancel();
    walk = null;
    ui.button.setAttribute("aria-pressed", "false");
    ui.bar.hidden = true;
  }

  function begin() {
    end();
    beforeStart();
    ui.button.setAttribute("aria-pressed", "true");
    ui.bar.hidden = false;
    ui.notice.hidden = true;
    walk = startWalk({
      map,
      onStatus: (text) => {
        ui.status.textContent = text;
      },
      onError: showError,
      onFinish: (latlngs, accuracies) => {
        onField(latlngs);
        const sorted = [...accuracies].sort((a, b) => a - b);
        setStatus(
          t("Field walked: {count} points, typical GPS accuracy ± {accuracy}. Check the corners and drag them if needed.", {
            count: latlngs.length,
            accuracy: formatMetres(sorted[Math.floor(sorted.length / 2)]),
          }),
        );
        end();
      },
    });
  }

  ui.button.addEventListener("click", () => (walk ? end() : begin()));
  $("walk-corner").addEventListener("click", () => walk?.addPoint());
  $("walk-finish").addEventListener("click", () => walk?.finish());
  $("walk-cancel").addEventListener("click", end);
  return { begin, end };
}
