// What the map page holds while it is open: its controls and its state, shared by the page's
// modules (map.js wires them; fieldedit.js, draft.js, planview.js and fieldimport.js act on them).

export const $ = (id) => document.getElementById(id);

export const ui = {
  app: $("app"),
  panel: $("panel"),
  panelToggle: $("panel-toggle"),
  language: $("language"),
  drawField: $("draw-field"),
  importField: $("import-field"),
  importFile: $("import-file"),
  setStart: $("set-start"),
  setFinish: $("set-finish"),
  clearAll: $("clear-all"),
  gotoForm: $("goto-form"),
  goto: $("goto"),
  interval: $("interval"),
  angle: $("angle"),
  objective: $("objective"),
  headland: $("headland"),
  speed: $("speed"),
  planName: $("plan-name"),
  generate: $("generate"),
  save: $("save-plan"),
  summary: $("summary"),
  summaryEmpty: $("summary-empty"),
  summaryFigures: $("summary-figures"),
  downloads: $("downloads"),
};

export const state = {
  map: null,
  api: null,
  field: null, // the editable L.Polygon
  markers: { start: null, finish: null },
  plan: null, // the last plan the API sent
  planDrawing: null, // what drawPlan returned, to remove it
  savedId: null, // the plan's id when what is shown is stored
  placing: null, // "start" | "finish" while waiting for a map click
  requestSeq: 0, // answers to superseded requests are dropped
  checks: null, // simulations and runs of the stored plan (checks.js)
  saved: null, // the Saved plans list (savedplans.js)
  fields: null, // the organisation's field registry (fields.js)
  parseUrl: null, // POST /api/fields/parse: the server's reader of field files
  importSeq: 0, // a newer import supersedes a field choice still open
  signedIn: false, // false while the server could not be reached to sign in (offline)
  walker: null, // Walk the boundary (walk.js)
  restoring: false, // while the draft is put back, changes are not stored again
};
