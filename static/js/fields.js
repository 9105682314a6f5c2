// The organisation's field registry on the page (product.md §12): the fields as outlines on the
// map and a list; choosing one puts it on the map to plan it, "Delete" asks about its plans.

import { csrfHeaders } from "./account.js";
import { t, tn } from "./i18n.js";

const $ = (id) => document.getElementById(id);

// Not interactive: clicks on the map belong to drawing; fields are chosen from the list.
const OUTLINE_STYLE = { color: "#f2c14e", weight: 2, dashArray: "4 4", fill: false };

async function call(url, method = "GET") {
  const response = await fetch(url, {
    method,
    headers: { Accept: "application/json", ...(method === "GET" ? {} : csrfHeaders()) },
    credentials: "same-origin",
  });
  if (!response.ok) throw new Error(`HTTP ${response.status}`);
  return response.status === 204 ? null : response.json();
}

/**
 * Show the registry and keep it fresh.
 * @param {{map: L.Map, apiUrl: string, loadField: function(object): void, onPlansChanged: function(): void}} hooks
 * @returns {{refresh: function(): Promise<void>}}
 */
export function setUpFields({ map, apiUrl, loadField, onPlansChanged }) {
  const outlines = L.layerGroup().addTo(map);

  function confirmDelete(item, field) {
    const box = document.createElement("div");
    box.className = "field-confirm";
    const question = document.createElement("span");
    question.textContent = field.plan_count
      ? tn("Delete {name}? It has {count} saved plan.", "Delete {name}? It has {count} saved plans.", field.plan_count, {
          name: field.name,
          count: field.plan_count,
        })
      : t("Delete {name}?", { name: field.name });
    const choices = [
      [t("Delete field and plans"), "delete"],
      [t("Delete field, keep plans"), "keep"],
    ];
    const buttons = choices.map(([text, plans]) => {
      const button = document.createElement("button");
      button.type = "button";
      button.className = "small";
      button.textContent = text;
      button.addEventListener("click", async () => {
        await call(`${apiUrl}/fields/${encodeURIComponent(field.id)}?plans=${plans}`, "DELETE");
        await refresh();
        if (plans === "delete") onPlansChanged();
      });
      return button;
    });
    const cancel = document.createElement("button");
    cancel.type = "button";
    cancel.className = "quiet small";
    cancel.textContent = t("Cancel");
    cancel.addEventListener("click", () => box.remove());
    box.append(question, ...buttons, cancel);
    item.append(box);
  }

  function fieldItem(field) {
    const item = document.createElement("li");
    item.dataset.id = String(field.id);
    const open = document.createElement("button");
    open.type = "button";
    open.className = "open-plan";
    open.setAttribute("aria-label", t("Plan {name}", { name: field.name }));
    const name = document.createElement("span");
    name.className = "plan-name";
    name.textContent = field.name;
    const meta = document.createElement("span");
    meta.className = "plan-meta";
    meta.textContent = tn("{count} plan", "{count} plans", field.plan_count, { count: field.plan_count });
    open.append(name, meta);
    open.addEventListener("click", () => loadField(field));
    const remove = document.createElement("button");
    remove.type = "button";
    remove.className = "quiet small";
    remove.textContent = t("Delete");
    remove.setAttribute("aria-label", t("Delete {name}", { name: field.name }));
    remove.addEventListener("click", () => confirmDelete(item, field));
    item.append(open, remove);
    return item;
  }

  async function refresh() {
    let listing;
    try {
      listing = await call(`${apiUrl}/fields`);
    } catch {
      return; // the list stays as it was; the plans' own errors say what is wrong
    }
    outlines.clearLayers();
    for (const field of listing.items) {
      L.geoJSON(field.boundary, { style: OUTLINE_STYLE, interactive: false }).addTo(outlines);
    }
    $("fields-list").replaceChildren(...listing.items.map(fieldItem));
    $("fields-empty").hidden = listing.items.length > 0;
  }

  refresh();
  return { refresh };
}
