// The map page: draw, walk or import a field, place start and finish, ask the API for a path,
// show it, save it, download it. The page holds what the person drew and typed (and keeps it on
// the phone as a draft); the API does all the planning (style.md §4), so nothing here computes
// geometry beyond drawing it. Every word shown goes through t() (i18n.js).

/* global L */

import { signIn } from "./account.js";
import { ChecksApi, PlansApi } from "./api.js";
import { createMap, FIELD_STYLE, setUpGeoman } from "./basemap.js";
import { setUpChecks } from "./checks.js";
import { restoreDraft, saveDraft } from "./draft.js";
import { adoptField, beginPlacing, checkSelfIntersection, endPlacing, onMapClick, startDrawing } from "./fieldedit.js";
import { importField, loadRegistryField, startOver } from "./fieldimport.js";
import { closeFieldChooser } from "./fieldpicker.js";
import { setUpFields } from "./fields.js";
import { restoreLanguageChoice, switchLanguage, t, tn } from "./i18n.js";
import {
  clearError,
  revealMapOnPhone,
  setPanelOpen,
  setStatus,
  showError,
  showFailure,
  showResultOnPhone,
  updateNotice,
} from "./messages.js";
import { registerServiceWorker, watchConnection } from "./offline.js";
import { state, ui } from "./pagestate.js";
import { deletePlan, generate, openPlan, removePlan } from "./planview.js";
import { setUpSavedPlans } from "./savedplans.js";
import { setUpVehicle } from "./vehicle.js";
import { goToCoordinates, setUpWalkControls } from "./walk.js";

/**
 * Sign in (account.js); with no connection, go on without: the page and the draft work, and
 * signing in happens when the network is back (before waiting saves are sent).
 */
async function ensureSignedIn(apiUrl) {
  if (state.signedIn) return true;
  try {
    await signIn(apiUrl);
    state.signedIn = true;
  } catch (error) {
    if (!(error instanceof TypeError)) throw error; // TypeError: fetch could not reach the server
  }
  return state.signedIn;
}

function wireControls() {
  ui.panelToggle.addEventListener("click", () =>
    setPanelOpen(ui.panelToggle.getAttribute("aria-expanded") !== "true"),
  );
  ui.language.addEventListener("change", () => switchLanguage(ui.language.value));
  ui.drawField.addEventListener("click", startDrawing);
  ui.importField.addEventListener("click", () => ui.importFile.click());
  ui.importFile.addEventListener("change", () => {
    const [file] = ui.importFile.files;
    ui.importFile.value = ""; // choosing the same file again must fire `change` again
    if (file) importField(file);
  });
  ui.setStart.addEventListener("click", () => beginPlacing("start"));
  ui.setFinish.addEventListener("click", () => beginPlacing("finish"));
  ui.gotoForm.addEventListener("submit", (event) => {
    event.preventDefault();
    clearError();
    if (goToCoordinates(state.map, ui.goto.value)) {
      ui.goto.removeAttribute("aria-invalid");
      revealMapOnPhone();
      setStatus(t("The map is at {position}.", { position: ui.goto.value.trim() }));
    } else {
      showError(t("Go to coordinates: “{typed}” is not a position. Type latitude and longitude in degrees, for example -8.6264, 115.2981.", { typed: ui.goto.value.trim() }));
      ui.goto.setAttribute("aria-invalid", "true");
      ui.goto.focus();
    }
  });
  ui.clearAll.addEventListener("click", startOver);
  ui.generate.addEventListener("click", () => generate());
  ui.save.addEventListener("click", () => generate({ save: true }));
  for (const control of [ui.interval, ui.angle, ui.speed, ui.planName, ui.objective, ui.headland]) {
    control.addEventListener("change", saveDraft);
    control.addEventListener("input", saveDraft);
  }
  // Enter in any text box plans, as a form would.
  for (const control of [ui.interval, ui.angle, ui.speed]) {
    control.addEventListener("keydown", (event) => {
      if (event.key === "Enter") generate();
    });
  }
  ui.planName.addEventListener("keydown", (event) => {
    if (event.key === "Enter") generate({ save: true });
  });
  document.addEventListener("keydown", (event) => {
    if (event.key === "Escape") {
      endPlacing();
      state.map.pm.disableDraw();
    }
  });
  state.map.on("click", onMapClick);
}

async function main() {
  if (!window.L?.PM) {
    document.getElementById("alert").textContent = t("The map library is missing on the server (run `npm ci`, or `make run`, which does it).");
    return;
  }
  restoreLanguageChoice();
  const dataset = ui.app.dataset;
  registerServiceWorker(dataset.serviceWorkerUrl); // first, so the page opens offline next time
  await ensureSignedIn(dataset.apiUrl);
  state.api = new PlansApi(dataset.plansUrl);
  closeFieldChooser();
  state.parseUrl = `${dataset.apiUrl.replace(/\/+$/, "")}/fields/parse`;
  state.map = createMap(dataset, {
    setStatus,
    showError,
    onWalk: () => state.walker.begin(),
    onGoto: () => {
      setPanelOpen(true);
      ui.goto.scrollIntoView({ block: "center" });
      ui.goto.focus();
    },
  });
  state.walker = setUpWalkControls({
    map: state.map,
    beforeStart: () => {
      endPlacing();
      clearError();
      state.map.pm.disableDraw();
      revealMapOnPhone();
    },
    onField: (latlngs) => adoptField(L.polygon(latlngs, FIELD_STYLE).addTo(state.map), { replot: false }),
    showError,
    setStatus,
  });
  setUpGeoman(state.map, {
    onCreate: (layer) => {
      adoptField(layer, { replot: false });
      checkSelfIntersection(layer);
    },
    onDrawEnd: () => setStatus(""),
    onCut: (original, layer) => {
      if (original === state.field) adoptField(layer, { replot: true });
    },
    onRemove: (layer) => {
      if (layer === state.field) {
        state.field = null;
        removePlan();
        saveDraft();
      }
    },
  });
  state.checks = setUpChecks({
    map: state.map,
    api: new ChecksApi(dataset.apiUrl),
    setStatus,
    showFailure,
    clearError,
    onResult: showResultOnPhone,
    onPlanCreated: async (plan) => {
      await state.saved.refresh();
      await openPlan(plan.id);
    },
  });
  state.saved = setUpSavedPlans({
    api: state.api,
    onOpen: (id) => openPlan(id),
    onDelete: deletePlan,
    showFailure,
    currentId: () => state.savedId,
  });
  state.fields = setUpFields({
    map: state.map,
    apiUrl: dataset.apiUrl,
    loadField: loadRegistryField,
    onPlansChanged: () => state.saved.refresh(),
  });
  wireControls();
  setUpVehicle(dataset.apiUrl);
  setPanelOpen(false);
  restoreDraft();
  if (state.signedIn) state.saved.refresh();
  watchConnection({
    api: state.api,
    beforeFlush: () => ensureSignedIn(dataset.apiUrl),
    onConnectionChange: updateNotice,
    onFlushed: ({ sent, refused }) => {
      updateNotice();
      if (sent.length > 0) {
        setStatus(tn("{count} plan saved offline has been sent.", "{count} plans saved offline have been sent.", sent.length, { count: sent.length }));
      }
      if (refused.length > 0) showFailure(refused[0].error);
      state.saved.refresh();
      state.fields?.refresh();
    },
  });
  updateNotice();
  ui.app.dataset.ready = "true"; // tests wait for this before clicking the map
}

main();
