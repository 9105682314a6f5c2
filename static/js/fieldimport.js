// Fields from elsewhere: a file imported (one field, or one chosen of many, or all into the
// registry), a field of the registry, and starting over.

import { postForm } from "./api.js";
import { saveDraft } from "./draft.js";
import { endPlacing, fieldFromPolygon, placeMarker } from "./fieldedit.js";
import { chooseField, closeFieldChooser, parseFieldFile } from "./fieldpicker.js";
import { t } from "./i18n.js";
import { clearError, setStatus, showFailure } from "./messages.js";
import { state, ui } from "./pagestate.js";
import { fitMap, removePlan } from "./planview.js";
import { forget, KEYS } from "./storage.js";

export async function importField(file) {
  endPlacing();
  clearError();
  try {
    const seq = ++state.importSeq;
    setStatus(t("Reading {file}…", { file: file.name }), { sticky: true });
    // The server reads every import format (GeoJSON, KML/KMZ, zipped Shapefile, GeoPackage).
    const { fields, start, finish } = await parseFieldFile(state.parseUrl, file, postForm);
    closeFieldChooser();
    if (fields.length > 1) {
      setStatus(t("Choose one of the {count} fields of {file}.", { count: fields.length, file: file.name }), {
        sticky: true,
      });
    }
    const chosen =
      fields.length === 1
        ? fields[0]
        : await chooseField(state.map, fields, {
            anchor: ui.importField.closest("section"),
            fileName: file.name,
            fit: fitMap,
            importAll: () => importAllFields(file),
          });
    if (chosen == null) {
      if (seq === state.importSeq) setStatus(""); // cancelled, not replaced by a newer import
      return;
    }
    state.map.pm.disableDraw();
    const layer = fieldFromPolygon(chosen.geometry);
    placeMarker("start", start);
    placeMarker("finish", finish);
    const { interval_m: intervalM, name, id } = chosen.properties ?? {};
    if (intervalM != null && intervalM > 0) ui.interval.value = String(intervalM);
    const title = name || id;
    if (title && !ui.planName.value.trim()) ui.planName.value = title;
    saveDraft();
    const bounds = layer.getBounds();
    for (const marker of Object.values(state.markers)) if (marker) bounds.extend(marker.getLatLng());
    fitMap(bounds);
    setStatus(t("Imported {file}. Check the interval, then press Generate path.", { file: file.name }));
  } catch (error) {
    setStatus("");
    showFailure(error);
  }
}

/** Store every field of `file` in the organisation's registry (POST /api/fields/import). */
async function importAllFields(file) {
  clearError();
  const form = new FormData();
  form.append("file", file, file.name);
  try {
    const { created, reused } = await postForm(state.parseUrl.replace(/parse$/, "import"), form);
    setStatus(
      t("Added {created} fields of {file} to your fields ({reused} were there already).", {
        created,
        file: file.name,
        reused,
      }),
    );
    state.fields?.refresh();
  } catch (error) {
    showFailure(error);
  }
}

export function startOver() {
  const drawn = state.field || state.markers.start || state.markers.finish;
  if (drawn && !window.confirm(t("Start over? The field, the start and the finish are removed from the map (saved plans stay)."))) {
    return;
  }
  closeFieldChooser();
  endPlacing();
  state.walker.end();
  clearError();
  state.map.pm.disableDraw();
  state.field?.remove();
  state.field = null;
  placeMarker("start", null);
  placeMarker("finish", null);
  removePlan();
  forget(KEYS.draft);
  setStatus("");
}

/** Put a field of the registry on the map, with its gates and name, ready to plan. */
export function loadRegistryField(field) {
  endPlacing();
  clearError();
  state.map.pm.disableDraw();
  const layer = fieldFromPolygon(field.boundary);
  placeMarker("start", field.start);
  placeMarker("finish", field.finish);
  ui.planName.value = field.name;
  saveDraft();
  fitMap(layer.getBounds());
  setStatus(t("{name}: check the interval, then press Generate path.", { name: field.name }));
}
