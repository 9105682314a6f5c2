// What the page keeps on the phone (localStorage): the map view, the draft (field, markers,
// inputs) and the saves waiting for the network. Private modes and locked-down browsers may
// refuse storage: then the page forgets, and still works.

export const KEYS = {
  view: "tillpath.view",
  baseLayer: "tillpath.baseLayer",
  draft: "tillpath.draft",
  outbox: "tillpath.outbox",
};

/** The stored value of `key`, or null. */
export function readStored(key) {
  try {
    return JSON.parse(localStorage.getItem(key));
  } catch {
    return null;
  }
}

/** Store `value` under `key`; answers false when the browser refused. */
export function store(key, value) {
  try {
    localStorage.setItem(key, JSON.stringify(value));
    return true;
  } catch {
    return false;
  }
}

export function forget(key) {
  try {
    localStorage.removeItem(key);
  } catch {
    // nothing to forget
  }
}
