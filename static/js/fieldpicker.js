// Importing a field file of any format (product.md §4): the server reads it (POST
// /api/fields/parse, the same reader as `tillpath plan FIELD`), and when the file holds several
// fields the person picks one, on the map or from a list. Nothing here parses KML, Shapefiles or
// GeoPackages: the page only shows what the API read.

/* global L */

import { ApiError } from "./api.js";
import { FieldFileError } from "./fieldfile.js";
import { formatArea } from "./format.js";
import { t, tapOrClick } from "./i18n.js";

/** Words shown to the person, in one place so that they can be translated. */
const TEXT = {
  heading: (count, file) => t("{file} holds {count} fields: choose one", { file, count }),
  hint: tapOrClick(t("Tap a field on the map or in the list."), t("Click a field on the map or in the list.")),
  cancel: t("Cancel"),
  importAll: (count) => t("Add all {count} to my fields", { count }),
  unnamed: (index) => t("Field {number}", { number: index + 1 }),
  refused: (detail) => t("Import field: {problem}", { problem: detail }),
};

/** Closes the chooser on screen, if any (a second import, or Start over). */
let closeOpenChooser = null;

/** Close the field chooser if one is open; its promise resolves with null. */
export function closeFieldChooser() {
  closeOpenChooser?.();
}

const CHOICE_STYLE = {
  color: "#8fd3ff",
  weight: 2,
  dashArray: "4 4",
  fillOpacity: 0.08,
  className: "field-choice-shape",
};
const HOVER_STYLE = { color: "#ffd54a", weight: 3, dashArray: null, fillOpacity: 0.25 };

/**
 * Send `file` to the server's reader; answer its fields and its start and finish.
 *
 * @param {string} parseUrl URL of POST /api/fields/parse.
 * @param {File} file The file the person chose.
 * @param {(url: string, form: FormData) => Promise<object>} post Sends a form, throws ApiError.
 * @returns {Promise<{fields: object[], start: number[]|null, finish: number[]|null}>}
 */
export async function parseFieldFile(parseUrl, file, post) {
  const form = new FormData();
  form.append("file", file, file.name);
  let collection;
  try {
    collection = await post(parseUrl, form);
  } catch (error) {
    // The server's words name the file and what is wrong with it: show them as they are.
    if (error instanceof ApiError && error.status === 422 && typeof error.detail === "string") {
      throw new FieldFileError(TEXT.refused(error.detail));
    }
    throw error;
  }
  const features = collection?.features ?? [];
  const point = (role) =>
    features.find((f) => f.geometry?.type === "Point" && f.properties?.role === role)?.geometry
      .coordinates ?? null;
  return {
    fields: features.filter((f) => f.geometry?.type === "Polygon"),
    start: point("start"),
    finish: point("finish"),
  };
}

function label(feature) {
  const { name, id, index } = feature.properties ?? {};
  return name || id || TEXT.unnamed(index ?? 0);
}

/**
 * Let the person pick one of several fields: each is drawn on the map and listed in a card
 * inserted after `anchor`. Resolves with the chosen Feature, or null when they cancel.
 *
 * @param {L.Map} map
 * @param {object[]} fields Polygon Features with `index`, `id`, `name`, `area_m2` properties.
 * @param {{anchor: HTMLElement, fileName: string, fit: (bounds: L.LatLngBounds) => void,
 *          importAll?: () => Promise<void>}} options `importAll` stores every field of the
 *   file in the registry (the chooser stays open to pick one to plan).
 * @returns {Promise<object|null>}
 */
export function chooseField(map, fields, { anchor, fileName, fit, importAll }) {
  closeFieldChooser();
  return new Promise((resolve) => {
    const card = document.createElement("section");
    card.className = "card field-chooser";
    card.id = "field-chooser";
    card.setAttribute("aria-labelledby", "field-chooser-heading");
    const heading = document.createElement("h2");
    heading.id = "field-chooser-heading";
    heading.textContent = TEXT.heading(fields.length, fileName);
    const hint = document.createElement("p");
    hint.className = "hint";
    hint.textContent = TEXT.hint;
    const list = document.createElement("ol");
    list.className = "field-choices";
    const cancel = document.createElement("button");
    cancel.type = "button";
    cancel.className = "quiet small";
    cancel.textContent = TEXT.cancel;

    const layers = new Map();
    const group = L.featureGroup().addTo(map);
    const done = (feature) => {
      closeOpenChooser = null;
      group.remove();
      card.remove();
      resolve(feature);
    };
    closeOpenChooser = () => done(null);
    fields.forEach((feature, position) => {
      const layer = L.geoJSON(feature, { style: CHOICE_STYLE });
      layer.bindTooltip(`${label(feature)} · ${formatArea(feature.properties?.area_m2)}`, { sticky: true });
      layer.on("click", (event) => {
        L.DomEvent.stopPropagation(event);
        done(feature);
      });
      layer.on("mouseover", () => layer.setStyle(HOVER_STYLE));
      layer.on("mouseout", () => layer.setStyle(CHOICE_STYLE));
      layer.addTo(group);
      layers.set(position, layer);

      const item = document.createElement("li");
      const button = document.createElement("button");
      button.type = "button";
      button.className = "field-choice";
      button.dataset.index = String(feature.properties?.index ?? position);
      const name = document.createElement("span");
      name.textContent = label(feature); // textContent: a file's names are never HTML
      const area = document.createElement("span");
      area.className = "field-choice-area";
      area.textContent = formatArea(feature.properties?.area_m2);
      button.append(name, area);
      button.addEventListener("click", () => done(feature));
      button.addEventListener("mouseenter", () => layer.setStyle(HOVER_STYLE));
      button.addEventListener("mouseleave", () => layer.setStyle(CHOICE_STYLE));
      item.append(button);
      list.append(item);
    });
    cancel.addEventListener("click", () => done(null));
    card.append(heading, hint, list);
    if (importAll) {
      const all = document.createElement("button");
      all.type = "button";
      all.className = "small";
      all.textContent = TEXT.importAll(fields.length);
      all.addEventListener("click", async () => {
        all.disabled = true;
        try {
          await importAll();
        } finally {
          all.disabled = false;
        }
      });
      card.append(all);
    }
    card.append(cancel);
    anchor.after(card);
    fit(group.getBounds());
    list.querySelector("button")?.focus();
  });
}
