// The draft: the field, the markers and the inputs kept on the phone, so that a reload or no
// network loses nothing.

import { fieldFromPolygon, fieldGeometry, markerLonLat, placeMarker } from "./fieldedit.js";
import { fillFormValues, formValues } from "./form.js";
import { state, ui } from "./pagestate.js";
import { generate, openPlan } from "./planview.js";
import { KEYS, readStored, store } from "./storage.js";

/** Keep the field, the markers and the inputs on the phone: a reload or no network loses nothing. */
export function saveDraft() {
  if (state.restoring) return;
  store(KEYS.draft, {
    field: state.field ? fieldGeometry({ quiet: true }) : null,
    start: markerLonLat("start"),
    finish: markerLonLat("finish"),
    form: formValues(ui),
    planned: state.plan != null,
    savedId: state.savedId,
  });
}

/** Put the draft back after a reload; open its stored plan, or plan it again, when online. */
export function restoreDraft() {
  const draft = readStored(KEYS.draft);
  if (!draft) return;
  state.restoring = true;
  try {
    fillFormValues(ui, draft.form);
    if (draft.field?.type === "Polygon") fieldFromPolygon(draft.field);
    placeMarker("start", draft.start);
    placeMarker("finish", draft.finish);
  } finally {
    state.restoring = false;
  }
  if (draft.savedId != null) openPlan(draft.savedId, { quiet: true, keepDraft: true });
  else if (draft.planned && state.field && navigator.onLine) generate({ quiet: true });
}
