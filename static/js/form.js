// The form's boxes: numbers typed with a point or a comma, what the draft keeps of them, and
// filling them from a stored plan. `ui` is the page's controls (map.js).

import { t } from "./i18n.js";

export const DEFAULT_SPEED_MPS = 0.56;

/** A decimal typed with a point or a comma; NaN when it is not a number, null when empty. */
export function parseDecimal(text) {
  const cleaned = text.trim().replace(",", ".");
  if (cleaned === "") return null;
  return /^[-+]?(\d+\.?\d*|\.\d+)$/.test(cleaned) ? Number(cleaned) : Number.NaN;
}

/** Check one number box; `example` is what to suggest typing. */
export function numberInput(control, label, { required = false, fallback = null, example }) {
  const value = parseDecimal(control.value);
  if (value === null && !required) return { value: fallback };
  if (value === null || Number.isNaN(value)) {
    const typed = control.value.trim();
    const error = typed
      ? t("{label}: “{typed}” is not a number. Type a number, for example {example}.", { label, typed, example })
      : t("{label}: this is empty. Type a number, for example {example}.", { label, example });
    return { error };
  }
  return { value };
}

/** What the form says, as typed (the draft keeps it even when it is not yet valid). */
export function formValues(ui) {
  return {
    interval: ui.interval.value,
    angle: ui.angle.value,
    objective: ui.objective.value,
    headland: ui.headland.value,
    speed: ui.speed.value,
    name: ui.planName.value,
  };
}

export function fillFormValues(ui, values) {
  if (!values) return;
  ui.interval.value = values.interval ?? "";
  ui.angle.value = values.angle ?? "";
  ui.objective.value = values.objective ?? "shortest_path";
  ui.headland.value = values.headland ?? "0";
  ui.speed.value = values.speed ?? String(DEFAULT_SPEED_MPS);
  ui.planName.value = values.name ?? "";
}

export function fillForm(ui, request, name) {
  ui.interval.value = request.interval_m ?? "";
  ui.angle.value = request.angle_deg ?? "";
  ui.objective.value = request.objective ?? "shortest_path";
  ui.headland.value = String(request.headland_passes ?? 0);
  ui.speed.value = request.speed_mps ?? DEFAULT_SPEED_MPS;
  ui.planName.value = name ?? request.name ?? "";
}

