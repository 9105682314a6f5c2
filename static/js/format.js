// Turning the API's SI figures and error strings into words and units a farmer reads at a glance,
// in the page's language: numbers through Intl (Indonesian writes 3,96 ha), words through t().

import { lang, t } from "./i18n.js";

const SQUARE_METRES_PER_HECTARE = 10_000;

const formats = new Map();

/** A number with exactly `digits` decimals, in the page's language (Indonesian: 3,96). */
export function formatNumber(value, digits = 0) {
  if (!formats.has(digits)) {
    formats.set(
      digits,
      new Intl.NumberFormat(lang, { minimumFractionDigits: digits, maximumFractionDigits: digits, useGrouping: "min2" }),
    );
  }
  return formats.get(digits).format(value);
}

/** Area in m² for small fields (with hectares beside it), in hectares from 1 ha up. */
export function formatArea(squareMetres) {
  if (!Number.isFinite(squareMetres)) return "–";
  const hectares = squareMetres / SQUARE_METRES_PER_HECTARE;
  if (hectares >= 1) return t("{area} ha", { area: formatNumber(hectares, 2) });
  return t("{area} m² ({hectares} ha)", {
    area: formatNumber(squareMetres, squareMetres < 1000 ? 1 : 0),
    hectares: formatNumber(hectares, hectares < 0.1 ? 3 : 2),
  });
}

/** Length in metres, or kilometres from 1 km up. */
export function formatLength(metres) {
  if (!Number.isFinite(metres)) return "–";
  if (metres >= 1000) return t("{length} km", { length: formatNumber(metres / 1000, 2) });
  return t("{length} m", { length: formatNumber(metres, metres < 100 ? 1 : 0) });
}

/** Duration as min:s (or h:mm:ss from one hour up), the way a stopwatch shows it. */
export function formatDuration(seconds) {
  if (!Number.isFinite(seconds)) return "–";
  const total = Math.round(seconds);
  const h = Math.floor(total / 3600);
  const m = Math.floor((total % 3600) / 60);
  const s = String(total % 60).padStart(2, "0");
  if (h > 0) return t("{time} h", { time: `${h}:${String(m).padStart(2, "0")}:${s}` });
  return t("{time} min", { time: `${m}:${s}` });
}

/** A 0–1 ratio as a percentage with one decimal. */
export function formatPercent(ratio) {
  if (!Number.isFinite(ratio)) return "–";
  return `${formatNumber(ratio * 100, 1)} %`;
}

/** A heading in degrees clockwise from north. */
export function formatAngle(degrees) {
  if (!Number.isFinite(degrees)) return "–";
  return `${formatNumber(degrees, 1)}°`;
}

/** An error or distance in metres with centimetres, or a dash when there is none. */
export function formatMetres(value) {
  if (!Number.isFinite(value)) return "–";
  return t("{length} m", { length: formatNumber(value, 2) });
}

/** The API names inputs as its JSON does; people know them by the labels on the page. */
export const INPUT_LABELS = {
  name: t("Plan name"),
  field: t("Field"),
  interval_m: t("Interval (m)"),
  start: t("Start"),
  finish: t("Finish"),
  angle_deg: t("Line angle (°)"),
  objective: t("Objective"),
  headland_passes: t("Headland passes"),
  speed_mps: t("Speed (m/s)"),
  file: t("Track file"),
  username: t("Username"),
  password: t("Password"),
  organisation: t("Organisation"),
};

/** Inputs whose problem reads as the end of a sentence about them ("This file has no fix."). */
const SENTENCE_INPUTS = {
  file: (problem) => t("This file {problem}", { problem }),
};

/** What to do about a problem with each input, added after the API's own words. */
const INPUT_ADVICE = {
  field: t("Edit the boundary on the map, or draw or import it again."),
  interval_m: t("The interval is the working width of the tractor in metres, for example 4."),
  start: t("Move the start marker nearer the field."),
  finish: t("Move the finish marker nearer the field."),
  angle_deg: t("Use 0 to 179, or leave it empty to let tillpath choose."),
  speed_mps: t("A hand tractor works at about 0.56 m/s."),
  file: t("Choose the tractor's log: a GPX track, a CSV file (time,lat,lon) or an NMEA log."),
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
      message: t(
        "Cannot reach the tillpath server: planning, saving and simulating need it. Your field and inputs are kept on this phone; try again when the connection is back.",
      ),
      input: null,
    };
  }
  if (status === 404) {
    return { message: t("This plan no longer exists; it may have been deleted."), input: null };
  }
  if (status === 413) {
    return {
      message: t("The field or file is too big to send. Simplify the boundary (fewer corners) or send a smaller file."),
      input: null,
    };
  }
  if (status >= 500) {
    return {
      message: t("Something went wrong on the server. Try again; if it keeps happening, tell the person who runs tillpath."),
      input: null,
    };
  }
  const { input, problem } = parseDetail(detailText(detail));
  if (!input) {
    const message = sentence(problem, { capitalise: true }) || t("The request was refused (error {status}).", { status: String(status) });
    return { message, input: null };
  }
  const advice = INPUT_ADVICE[input] ? ` ${INPUT_ADVICE[input]}` : "";
  if (SENTENCE_INPUTS[input]) return { message: SENTENCE_INPUTS[input](sentence(problem)) + advice, input };
  return { message: t("{input}: {problem}", { input: INPUT_LABELS[input], problem: sentence(problem) }) + advice, input };
}

/** A saved plan's date in the reader's own words and time zone. */
export function formatDate(isoText) {
  const date = new Date(isoText);
  if (Number.isNaN(date.getTime())) return "";
  return date.toLocaleString(lang, { dateStyle: "medium", timeStyle: "short" });
}
