// The "Saved plans" list: a page of plans at a time, newest first, searchable by name
// (GET /api/plans?q=&limit=&offset=), each with Open and Delete.

import { formatArea, formatDate } from "./format.js";
import { t, tn } from "./i18n.js";

/** Plans shown per page. */
export const PAGE_SIZE = 20;
/** Typing pauses this long before the list is searched again [ms]. */
const SEARCH_DELAY_MS = 250;

const $ = (id) => document.getElementById(id);

export function planTitle(plan) {
  return plan.name || t("Plan {id}", { id: String(plan.id) });
}

/**
 * Wire the Saved plans card.
 *
 * @param {object} options
 * @param {PlansApi} options.api
 * @param {(id: number) => void} options.onOpen
 * @param {(id: number, title: string) => void} options.onDelete
 * @param {(error: unknown) => void} options.showFailure
 * @param {() => number|null} options.currentId The id of the plan on the map, if stored.
 * @returns {{refresh: () => Promise<void>, markCurrent: () => void}}
 */
export function setUpSavedPlans({ api, onOpen, onDelete, showFailure, currentId }) {
  const ui = {
    list: $("saved-plans"),
    empty: $("saved-empty"),
    search: $("plan-search"),
    pager: $("saved-pager"),
    newer: $("saved-newer"),
    older: $("saved-older"),
    range: $("saved-range"),
  };
  const state = { offset: 0, total: 0, seq: 0, timer: null };

  function markCurrent() {
    const id = currentId();
    for (const item of ui.list.children) {
      const current = id != null && item.dataset.id === String(id);
      item.classList.toggle("current", current);
      if (current) item.setAttribute("aria-current", "true");
      else item.removeAttribute("aria-current");
    }
  }

  function item(plan) {
    const title = planTitle(plan);
    const li = document.createElement("li");
    li.dataset.id = String(plan.id);
    const open = document.createElement("button");
    open.type = "button";
    open.className = "open-plan";
    open.setAttribute("aria-label", t("Open {name}", { name: title }));
    const name = document.createElement("span");
    name.className = "plan-name";
    name.textContent = title;
    const meta = document.createElement("span");
    meta.className = "plan-meta";
    const stats = plan.stats ?? {};
    const lines = Number.isFinite(stats.line_count)
      ? tn("{count} line", "{count} lines", stats.line_count, { count: stats.line_count })
      : "";
    meta.textContent = [formatDate(plan.created_at), lines, formatArea(stats.area_m2)].filter(Boolean).join(" · ");
    open.append(name, meta);
    open.addEventListener("click", () => onOpen(plan.id));
    const remove = document.createElement("button");
    remove.type = "button";
    remove.className = "delete-plan quiet";
    remove.textContent = t("Delete");
    remove.setAttribute("aria-label", t("Delete {name}", { name: title }));
    remove.addEventListener("click", () => onDelete(plan.id, title));
    li.append(open, remove);
    return li;
  }

  async function refresh() {
    const seq = ++state.seq;
    const q = ui.search.value.trim();
    try {
      let page = await api.list({ limit: PAGE_SIZE, offset: state.offset, q });
      if (page.items.length === 0 && state.offset > 0 && page.total > 0) {
        // The last plan of the last page was deleted: show the page before it.
        state.offset = Math.max(0, Math.floor((page.total - 1) / PAGE_SIZE) * PAGE_SIZE);
        page = await api.list({ limit: PAGE_SIZE, offset: state.offset, q });
      }
      if (seq !== state.seq) return;
      const { items, total } = page;
      state.total = total;
      ui.list.replaceChildren(...items.map(item));
      ui.empty.hidden = items.length > 0;
      ui.empty.textContent = q ? t("No saved plan has “{query}” in its name.", { query: q }) : t("No saved plans yet.");
      ui.pager.hidden = total <= PAGE_SIZE;
      ui.newer.disabled = state.offset === 0;
      ui.older.disabled = state.offset + items.length >= total;
      ui.range.textContent = t("{first}–{last} of {total}", {
        first: items.length ? state.offset + 1 : 0,
        last: state.offset + items.length,
        total,
      });
      markCurrent();
    } catch (error) {
      if (seq === state.seq) showFailure(error);
    }
  }

  ui.search.addEventListener("input", () => {
    clearTimeout(state.timer);
    state.timer = setTimeout(() => {
      state.offset = 0;
      refresh();
    }, SEARCH_DELAY_MS);
  });
  ui.newer.addEventListener("click", () => {
    state.offset = Math.max(0, state.offset - PAGE_SIZE);
    refresh();
  });
  ui.older.addEventListener("click", () => {
    state.offset += PAGE_SIZE;
    refresh();
  });
  return { refresh, markCurrent };
}
