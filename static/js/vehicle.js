// The vehicle and implement of a plan (product.md §3a): which machine drives the path, how wide
// its implement tills, and in which order it takes the lines. The presets and their figures
// come from the API (GET /api/vehicles); this module only shows them and puts the choice in
// the request. No geometry here: the planner fits the turns.

import { t } from "./i18n.js";

const $ = (id) => document.getElementById(id);

/** What the page calls each preset, in words a farmer knows (in the page's language). */
function presetName(preset) {
  const names = {
    hand_tractor: t("Hand tractor (walk-behind)"),
    paper_g1000: t("Quick G1000 (the paper's figures)"),
    small_tractor: t("Small four-wheel tractor"),
    rover: t("Field robot (skid-steer)"),
  };
  return names[preset] ?? preset;
}

const ui = {
  vehicle: null,
  implement: null,
  pattern: null,
  figures: null,
};

let presets = {};

function parseDecimal(text) {
  const trimmed = text.trim().replace(",", ".");
  if (trimmed === "") return null;
  const value = Number(trimmed);
  return Number.isFinite(value) ? value : Number.NaN;
}

/** The chosen vehicle's figures, as a sentence: width, track, turning radius, reversing. */
function describe(vehicle) {
  if (!vehicle) return "";
  const turning =
    vehicle.min_turn_radius_m > 0
      ? t("turns on a {radius} m radius", { radius: vehicle.min_turn_radius_m })
      : t("pivots about a wheel ({track} m track)", { track: vehicle.track_m });
  const reverse = vehicle.can_reverse ? t("may reverse") : t("forward only");
  return t("{width} m wide, {length} m long, {turning}, {reverse}.", {
    width: vehicle.width_m,
    length: vehicle.length_m,
    turning,
    reverse,
  });
}

function showFigures() {
  ui.figures.textContent = describe(presets[ui.vehicle.value]);
}

/**
 * Fill the vehicle choice from the API; the page works with the default vehicle meanwhile.
 * @param {string} apiUrl the API root the server put in the page
 */
export async function setUpVehicle(apiUrl) {
  ui.vehicle = $("vehicle");
  ui.implement = $("implement-width");
  ui.pattern = $("pattern");
  ui.figures = $("vehicle-figures");
  if (!ui.vehicle) return;
  ui.vehicle.addEventListener("change", showFigures);
  try {
    const response = await fetch(`${apiUrl}/vehicles`, { headers: { Accept: "application/json" } });
    if (!response.ok) return;
    const { items } = await response.json();
    presets = Object.fromEntries(items.map((v) => [v.preset, v]));
    const chosen = ui.vehicle.value;
    ui.vehicle.replaceChildren(
      ...items.map((v) => {
        const option = document.createElement("option");
        option.value = v.preset;
        option.textContent = presetName(v.preset);
        option.selected = v.preset === chosen;
        return option;
      }),
    );
    showFigures();
  } catch {
    // Offline or refused: the built-in option (hand tractor) stays.
  }
}

/**
 * The request fields this module owns, or `{error, input}` when the implement width is not a number.
 */
export function vehicleRequest() {
  if (!ui.vehicle) return {};
  const width = parseDecimal(ui.implement.value);
  if (Number.isNaN(width)) {
    return {
      error: t("Implement width (m): “{typed}” is not a number. Leave it empty to use the interval.", {
        typed: ui.implement.value.trim(),
      }),
      input: "implement_width_m",
    };
  }
  return { vehicle: ui.vehicle.value, implement_width_m: width, pattern: ui.pattern.value };
}

/** Show a stored request's vehicle, implement width and pattern. */
export function fillVehicle(request) {
  if (!ui.vehicle) return;
  const vehicle = request.vehicle ?? "hand_tractor";
  const preset = typeof vehicle === "string" ? vehicle : (vehicle.preset ?? "hand_tractor");
  if ([...ui.vehicle.options].some((o) => o.value === preset)) ui.vehicle.value = preset;
  ui.implement.value = request.implement_width_m ?? "";
  ui.pattern.value = request.pattern ?? "boustrophedon";
  showFigures();
}
