// Missed ground and the receiver behind a run (product.md §8): the field the run's implement
// footprint did not cover, drawn as polygons, a button that plans a follow-up path over them,
// and a plain sentence on how good the run's fixes were. Every polygon comes from the API.

/* global L */

import { formatPercent } from "./format.js";

const MISSED_STYLE = { color: "#ff6d00", weight: 2, opacity: 0.95, fillColor: "#ff6d00", fillOpacity: 0.35 };

/** Draw a run's missed ground into `group`; return how many gaps there are. */
export function drawMissed(group, run) {
  const features = run.missed?.features ?? [];
  for (const feature of features) {
    L.geoJSON(feature, { style: () => ({ ...MISSED_STYLE, className: "missed-ground" }), pmIgnore: true })
      .bindTooltip(`Missed: ${feature.properties.area_m2.toFixed(1)} m²`)
      .addTo(group);
  }
  return features.length;
}

/** "12.3 m² in 2 gaps (4.1 % of the field)", or that nothing was missed. */
export function missedText(run) {
  const features = run.missed?.features ?? [];
  if (!run.fix_count) return "–";
  if (features.length === 0) return "none";
  const props = run.missed.properties ?? {};
  const gaps = features.length === 1 ? "1 gap" : `${features.length} gaps`;
  return `${(props.area_m2 ?? 0).toFixed(1)} m² in ${gaps} (${formatPercent(props.field_share)} of the field)`;
}

/** What the run's receiver was worth, in the API's own words, with the share of each fix. */
export function receiverText(run) {
  const receiver = run.receiver;
  if (!receiver || !run.fix_count) return "";
  const names = { rtk_fixed: "RTK fixed", rtk_float: "RTK float", dgps: "DGPS", single: "single", dead_reckoning: "dead reckoning" };
  const shares = Object.entries(names)
    .filter(([key]) => receiver.shares?.[key] > 0)
    .map(([key, label]) => `${label} ${formatPercent(receiver.shares[key])}`);
  return [receiver.note, shares.length ? `Fixes: ${shares.join(", ")}.` : ""].filter(Boolean).join(" ");
}
