// The plans API (product.md §5). Every URL derives from the one the server put in the page, so
// the page keeps working behind a proxy or under a path prefix. Requests ask for errors in the
// page's language (Accept-Language), so the API's words match the page's.

import { csrfHeaders } from "./account.js";

const LANGUAGE = document.documentElement.lang || "en";

/** A refused or failed request: `status` is 0 when the server could not be reached. */
export class ApiError extends Error {
  constructor(status, detail) {
    super(typeof detail === "string" ? detail : `HTTP ${status}`);
    this.name = "ApiError";
    this.status = status;
    this.detail = detail;
  }
}

/** Send a request; answer its JSON, or throw an ApiError with the server's `detail`. */
async function send(url, options) {
  let response;
  try {
    const write = (options.method ?? "GET") !== "GET" ? csrfHeaders() : {};
    response = await fetch(url, {
      ...options,
      credentials: "same-origin",
      headers: { Accept: "application/json", "Accept-Language": LANGUAGE, ...write, ...options.headers },
    });
  } catch {
    throw new ApiError(0, null);
  }
  if (!response.ok) {
    let detail = null;
    try {
      detail = (await response.json()).detail ?? null;
    } catch {
      // Not JSON (a proxy's error page, say): the status alone has to do.
    }
    throw new ApiError(response.status, detail);
  }
  return response.status === 204 ? null : response.json();
}

function requestJson(url, { method = "GET", body } = {}) {
  if (body === undefined) return send(url, { method });
  return send(url, { method, headers: { "Content-Type": "application/json" }, body: JSON.stringify(body) });
}

/** Client for one tillpath server, given the URL of its plans collection. */
export class PlansApi {
  constructor(plansUrl) {
    this.plansUrl = plansUrl.replace(/\/+$/, "");
  }

  planUrl(id) {
    return `${this.plansUrl}/${encodeURIComponent(id)}`;
  }

  exportUrl(id, format) {
    return `${this.planUrl(id)}/export/${format}`;
  }

  /** Plan without storing (POST /preview). */
  preview(request) {
    return requestJson(`${this.plansUrl}/preview`, { method: "POST", body: request });
  }

  /** Plan and store; the answer carries the new `id`. */
  create(request) {
    return requestJson(this.plansUrl, { method: "POST", body: request });
  }

  /** Newest first: `{items, total}`; `q` keeps the plans whose name contains it. */
  list({ limit = 50, offset = 0, q = "" } = {}) {
    const query = new URLSearchParams({ limit: String(limit), offset: String(offset) });
    if (q) query.set("q", q);
    return requestJson(`${this.plansUrl}?${query}`);
  }

  read(id) {
    return requestJson(this.planUrl(id));
  }

  remove(id) {
    return requestJson(this.planUrl(id), { method: "DELETE" });
  }
}

function requestForm(url, form) {
  return send(url, { method: "POST", body: form });
}

/** POST a multipart form (a file upload); answer the JSON or throw an ApiError. */
export function postForm(url, form) {
  return requestForm(url, form);
}

/** Simulations and runs (product.md §5, §7, §8), given the API root (`…/api`). */
export class ChecksApi {
  constructor(apiUrl) {
    this.apiUrl = apiUrl.replace(/\/+$/, "");
  }

  /**
   * Simulate a stored plan: `{seed, gps, guidance}`; the answer has metrics and the true track,
   * thinned for drawing (`tracks=display`; the GPX export has every second of all three).
   */
  simulate(planId, body) {
    return requestJson(`${this.apiUrl}/plans/${encodeURIComponent(planId)}/simulations?tracks=display`, {
      method: "POST",
      body,
    });
  }

  /** A plan's stored simulations, newest first: `{items, total}` (metrics, no tracks). */
  listSimulations(planId) {
    return requestJson(`${this.apiUrl}/plans/${encodeURIComponent(planId)}/simulations`);
  }

  readSimulation(id) {
    return requestJson(`${this.apiUrl}/simulations/${encodeURIComponent(id)}?tracks=display`);
  }

  simulationGpxUrl(id) {
    return `${this.apiUrl}/simulations/${encodeURIComponent(id)}/export/gpx`;
  }

  simulationKmlUrl(id) {
    return `${this.apiUrl}/simulations/${encodeURIComponent(id)}/export/kml`;
  }

  /** Upload a recorded track (GPX, CSV or NMEA) as a new run of the plan. */
  uploadRun(planId, file) {
    const form = new FormData();
    form.append("file", file, file.name);
    return requestForm(`${this.apiUrl}/plans/${encodeURIComponent(planId)}/runs`, form);
  }

  listRuns(planId) {
    return requestJson(`${this.apiUrl}/plans/${encodeURIComponent(planId)}/runs`);
  }

  readRun(id) {
    return requestJson(`${this.apiUrl}/runs/${encodeURIComponent(id)}`);
  }

  runGpxUrl(id) {
    return `${this.apiUrl}/runs/${encodeURIComponent(id)}/export/gpx`;
  }

  runKmlUrl(id) {
    return `${this.apiUrl}/runs/${encodeURIComponent(id)}/export/kml`;
  }
}
