// Turning the API's SI figures and error strings into words and units a farmer reads at a glance.

const SQUARE_METRES_PER_HECTARE = 10_000;

/** Area in m² for small fields (with hectares beside it), in hectares from 1 ha up. */
export function formatArea(squareMetres) {
  if (!Number.isFinite(squareMetres)) return "–";
  const hectares = squareMetres / SQUARE_METRES_PER_HECTARE;
  if (hectares >= 1) return `${hectares.toFixed(2)} ha`;
  const m2 = squareMetres.toFixed(squareMetres < 1000 ? 1 : 0);
  return `${m2} m² (${hectares.toFixed(hectares < 0.1 ? 3 : 2)} ha)`;
}

/** Length in metres, or kilometres from 1 km up. */
export function formatLength(metres) {
  if (!Number.isFinite(metres)) return "–";
  if (metres >= 1000) return `${(metres / 1000).toFixed(2)} km`;
  return `${metres.toFixed(metres < 100 ? 1 : 0)} m`;
}

/** Duration as min:s (or h:mm:ss from one hour up), the way a stopwatch shows it. */
export function formatDuration(seconds) {
  if (!Number.isFinite(seconds)) return "–";
  const total = Math.round(seconds);
  const h = Math.floor(total / 3600);
  const m = Math.floor((total % 3600) / 60);
  const s = String(total % 60).padStart(2, "0");
  if (h > 0) return `${h}:${String(m).padStart(2, "0")}:${s} h`;
  return `${m}:${s} min`;
}

/** A 0–1 ratio as a percentage with one decimal. */
export function formatPercent(ratio) {
  if (!Number.isFinite(ratio)) return "–";
  return `${(ratio * 100).toFixed(1)} %`;
}

/** A heading in degrees clockwise from north. */
export function formatAngle(degrees) {
  if (!Number.isFinite(degrees)) return "–";
  return `${degrees.toFixed(1)}°`;
}

/** The API names inputs as its JSON does; people know them by the labels on the page. */
export const INPUT_LABELS = {
  name: "Plan name",
  field: "Field",
  interval_m: "Interval (m)",
  start: "Start",
  finish: "Finish",
  angle_deg: "Line angle (°)",
  objective: "Objective",
  headland_passes: "Headland passes",
  speed_mps: "Speed (m/s)",
};

/** What to do about a problem with each input, added after the API's own words. */
const INPUT_ADVICE = {
  field: "Edit the boundary on the map, or draw or import it again.",
  interval_m: "The interval is the working width of the tractor in metres, for example 4.",
  start: "Move the start marker nearer the field.",
  finish: "Move the finish marker nearer the field.",
  angle_deg: "Use 0 to 179, or leave it empty to let tillpath choose.",
  speed_mps: "A hand tractor works at about 0.56 m/s.",
};

/**
 * Split an API error such as "interval_m: must be between 0.2 and 50" into the input it names
 * and the problem. Returns {input: null} when the text does not start with a known input.
 */
export function parseDetail(detail) {
  const match = /^([a-z_]+)(?:[.[][^:]*)?:\s*(.+)$/s.exec(detail ?? "");
  if (match && match[1] in INPUT_LABELS) return { input: match[1], problem: match[2] };
  return { input: null, problem: detail ?? "" };
}

/** Join FastAPI's default validation errors (a list) into one "input: problem" string. */
function detailText(detail) {
  if (typeof detail === "string") return detail;
  if (Array.isArray(detail) && detail.length > 0) {
    const first = detail[0];
    const loc = (first.loc ?? []).filter((part) => part !== "body").join(".");
    return loc ? `${loc}: ${first.msg}` : String(first.msg);
  }
  return "";
}

/** End `text` as a sentence; capitalise it only when it starts one (not after a label). */
function sentence(text, { capitalise = false } = {}) {
  const trimmed = text.trim();
  if (!trimmed) return "";
  const start = capitalise ? trimmed[0].toUpperCase() + trimmed.slice(1) : trimmed;
  return /[.!?]$/.test(start) ? start : `${start}.`;
}

/**
 * Words for a failed request: what went wrong, with the input's label and what to do.
 *
 * @param {number} status HTTP status, or 0 when the server could not be reached.
 * @param {unknown} detail The response's `detail` (a string from tillpath's API).
 * @returns {{message: string, input: string|null}} The text to show and the input to point at.
 */
export function friendlyError(status, detail) {
  if (status === 0) {
    return {
      message: "Cannot reach the tillpath server. Check the connection and try again.",
      input: null,
    };
  }
  if (status === 404) {
    return { message: "This plan no longer exists; it may have been deleted.", input: null };
  }
  if (status === 413) {
    return {
      message: "The field is too big to send. Simplify the boundary (fewer corners) and try again.",
      input: null,
    };
  }
  if (status >= 500) {
    return {
      message: "Something went wrong on the server. Try again; if it keeps happening, tell the person who runs tillpath.",
      input: null,
    };
  }
  const { input, problem } = parseDetail(detailText(detail));
  if (!input) return { message: sentence(problem, { capitalise: true }) || `The request was refused (error ${status}).`, input: null };
  const advice = INPUT_ADVICE[input] ? ` ${INPUT_ADVICE[input]}` : "";
  return { message: `${INPUT_LABELS[input]}: ${sentence(problem)}${advice}`, input };
}

/** A saved plan's date in the reader's own words and time zone. */
export function formatDate(isoText) {
  const date = new Date(isoText);
  if (Number.isNaN(date.getTime())) return "";
  return date.toLocaleString(undefined, { dateStyle: "medium", timeStyle: "short" });
}
