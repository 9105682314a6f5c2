// Missed ground and the receiver behind a run (product.md §8): the field the run's implement
// footprint did not cover, drawn as polygons, a button that plans a follow-up path over them,
// and a plain sentence on how good the run's fixes were. Every polygon comes from the API.

/* global L */

import { formatPercent } from "./format.js";
import { t } from "./i18n.js";

const MISSED_STYLE = { color: "#ff6d00", weight: 2, opacity: 0.95, fillColor: "#ff6d00", fillOpacity: 0.35 };

/** Draw a run's missed ground into `group`; return how many gaps there are. */
export function drawMissed(group, run) {
  const features = run.missed?.features ?? [];
  for (const feature of features) {
    L.geoJSON(feature, { style: () => ({ ...MISSED_STYLE, className: "missed-ground" }), pmIgnore: true })
      .bindTooltip(t("Missed: {area} m²", { area: feature.properties.area_m2.toFixed(1) }))
      .addTo(group);
  }
  return features.length;
}

/** The API's notes on what a run's figures are worth, by accuracy (app/receiver.py). */
const NOTES = {
  centimetre: t("RTK fixed: the figures are accurate to a few centimetres."),
  decimetre: t(
    "RTK float or mixed RTK: the figures are accurate to a few decimetres; cross-track errors below that are not measurable.",
  ),
  metre: t(
    "These figures rest on a receiver of metre-level accuracy (single or DGPS fixes, like a u-blox NEO-M8N's 2.5 m CEP): cross-track errors, waypoint errors and coverage are estimates that can be off by a couple of metres.",
  ),
  unknown: t(
    "The log does not say how good its fixes were. If it came from a single-frequency receiver such as a u-blox NEO-M8N, treat these figures as metre-level estimates.",
  ),
};

/** "12.3 m² in 2 gaps (4.1 % of the field)", or that nothing was missed. */
export function missedText(run) {
  const features = run.missed?.features ?? [];
  if (!run.fix_count) return "–";
  if (features.length === 0) return t("none");
  const props = run.missed.properties ?? {};
  return t("{area} m² in {gaps} gap(s) ({share} of the field)", {
    area: (props.area_m2 ?? 0).toFixed(1),
    gaps: features.length,
    share: formatPercent(props.field_share),
  });
}

/** What the run's receiver was worth, in the API's own words, with the share of each fix. */
export function receiverText(run) {
  const receiver = run.receiver;
  if (!receiver || !run.fix_count) return "";
  const names = {
    rtk_fixed: t("RTK fixed"),
    rtk_float: t("RTK float"),
    dgps: "DGPS",
    single: t("single"),
    dead_reckoning: t("dead reckoning"),
  };
  const shares = Object.entries(names)
    .filter(([key]) => receiver.shares?.[key] > 0)
    .map(([key, label]) => `${label} ${formatPercent(receiver.shares[key])}`);
  const note = NOTES[receiver.accuracy] ?? receiver.note;
  return [note, shares.length ? t("Fixes: {shares}.", { shares: shares.join(", ") }) : ""]
    .filter(Boolean)
    .join(" ");
}
