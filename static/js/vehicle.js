// The vehicle and implement of a plan (product.md §3a): which machine drives the path, how wide
// its implement tills, and in which order it takes the lines. The presets and their figures
// come from the API (GET /api/vehicles); this module only shows them and puts the choice in
// the request. No geometry here: the planner fits the turns.

const $ = (id) => document.getElementById(id);

/** What the page calls each preset, in words a farmer knows. */
const PRESET_NAMES = {
  hand_tractor: "Hand tractor (walk-behind)",
  paper_g1000: "Quick G1000 (the paper's figures)",
  small_tractor: "Small four-wheel tractor",
  rover: "Field robot (skid-steer)",
};

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
      ? `turns on a ${vehicle.min_turn_radius_m} m radius`
      : `pivots about a wheel (${vehicle.track_m} m track)`;
  const reverse = vehicle.can_reverse ? ", may reverse" : ", forward only";
  return `${vehicle.width_m} m wide, ${vehicle.length_m} m long, ${turning}${reverse}.`;
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
        option.textContent = PRESET_NAMES[v.preset] ?? v.preset;
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
      error: `Implement width (m): “${ui.implement.value.trim()}” is not a number. Leave it empty to use the interval.`,
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

/** The form controls of this module's inputs, to point at one the API refused. */
export function vehicleControls() {
  return { vehicle: ui.vehicle, implement_width_m: ui.implement, pattern: ui.pattern };
}
