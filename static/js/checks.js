// Simulations and field runs on the map page (product.md §7, §8): the Simulate and Upload track
// buttons, the simulated or recorded track drawn over the plan, its metrics beside the Plan
// summary, and a live run that grows while the tractor's logger streams fixes. Every figure and
// every coordinate comes from the API.

/* global L */

import { formatDate, formatDuration, formatPercent } from "./format.js";

/** How often a live run is fetched again [ms]. */
export const LIVE_POLL_MS = 3000;

const SIM_STYLE = { color: "#76ff03", weight: 3, opacity: 0.95 };
const RUN_STYLE = { color: "#ff4df0", weight: 3, opacity: 0.95 };
const OFF_LINE_STYLE = { color: "#ff2d2d", weight: 7, opacity: 0.85, lineCap: "round" };

const $ = (id) => document.getElementById(id);

/** An error in metres with centimetres, or a dash when there is none. */
function formatMetres(value) {
  return Number.isFinite(value) ? `${value.toFixed(2)} m` : "–";
}

function latLngs(coordinates) {
  return coordinates.map(([lon, lat]) => [lat, lon]);
}

function fillFigures(container, metrics, extra = {}) {
  const figures = {
    time: formatDuration(metrics?.time_s),
    coverage: formatPercent(metrics?.coverage_ratio),
    wp_max: formatMetres(metrics?.waypoint_error_max_m),
    wp_mean: formatMetres(metrics?.waypoint_error_mean_m),
    xte_rms: formatMetres(metrics?.cross_track_rms_m),
    completed: metrics ? (metrics.completed ? "yes" : "no") : "–",
    ...extra,
  };
  for (const [key, text] of Object.entries(figures)) {
    const cell = container.querySelector(`[data-metric="${key}"]`);
    if (cell) cell.textContent = text;
  }
}

function stretchesText(metrics) {
  if (!metrics) return "–";
  const n = metrics.stretches.length;
  if (n === 0) return `never more than ${formatMetres(metrics.threshold_m)} off a line`;
  const seconds = metrics.stretches.reduce((sum, s) => sum + s.duration_s, 0);
  return `${n} stretch${n === 1 ? "" : "es"} over ${formatMetres(metrics.threshold_m)}, ${formatDuration(seconds)} in all`;
}

/**
 * Wire the Simulate and Upload track controls.
 *
 * @param {object} options
 * @param {L.Map} options.map
 * @param {ChecksApi} options.api
 * @param {(text: string) => void} options.setStatus
 * @param {(error: unknown) => void} options.showFailure
 * @param {() => void} options.clearError
 * @returns {{planChanged: (planId: number | null) => void}}
 */
export function setUpChecks({ map, api, setStatus, showFailure, clearError }) {
  const ui = {
    card: $("check"),
    gps: $("sim-gps"),
    guidance: $("sim-guidance"),
    simulate: $("simulate"),
    upload: $("upload-track"),
    file: $("track-file"),
    hint: $("check-hint"),
    simulation: $("simulation"),
    simulationTitle: $("simulation-title"),
    simulationGpx: $("simulation-gpx"),
    simulationKml: $("simulation-kml"),
    run: $("run"),
    runTitle: $("run-title"),
    runGpx: $("run-gpx"),
    runKml: $("run-kml"),
    runs: $("runs-list"),
    runsEmpty: $("runs-empty"),
  };
  const state = { planId: null, simLayer: null, runLayer: null, runId: null, run: null, timer: null, seq: 0 };

  function setEnabled() {
    const enabled = state.planId != null;
    ui.simulate.disabled = !enabled;
    ui.upload.disabled = !enabled;
    ui.hint.textContent = enabled
      ? "Upload the tractor's log: a GPX track, a CSV file (time,lat,lon) or a u-blox NMEA log."
      : "Save the plan first, then simulate it or upload the tractor's track.";
  }

  function stopPolling() {
    clearTimeout(state.timer);
    state.timer = null;
  }

  function clearSimulation() {
    state.simLayer?.remove();
    state.simLayer = null;
    ui.simulation.hidden = true;
  }

  function clearRun() {
    stopPolling();
    state.runLayer?.remove();
    state.runLayer = null;
    state.runId = null;
    ui.run.hidden = true;
  }

  function showSimulation(simulation) {
    clearSimulation();
    const track = simulation.tracks.features.find((f) => f.properties?.source === "true");
    state.simLayer = L.polyline(latLngs(track.geometry.coordinates), {
      ...SIM_STYLE,
      pmIgnore: true,
      className: "simulated-track",
    }).addTo(map);
    const { gps, guidance, seed } = simulation.config;
    ui.simulationTitle.textContent = `(${gps}, ${guidance}, seed ${seed})`;
    fillFigures(ui.simulation, simulation.metrics);
    ui.simulationGpx.href = api.simulationGpxUrl(simulation.id);
    ui.simulationKml.href = api.simulationKmlUrl(simulation.id);
    ui.simulation.hidden = false;
  }

  function showRun(run) {
    state.runLayer?.remove();
    state.runId = run.id;
    state.run = run;
    const group = L.layerGroup();
    if (run.track) {
      L.polyline(latLngs(run.track.geometry.coordinates), {
        ...RUN_STYLE,
        pmIgnore: true,
        className: "run-track",
      }).addTo(group);
    }
    for (const stretch of run.stretches?.features ?? []) {
      const p = stretch.properties;
      L.polyline(latLngs(stretch.geometry.coordinates), {
        ...OFF_LINE_STYLE,
        pmIgnore: true,
        className: "off-line-stretch",
      })
        .bindTooltip(`Up to ${formatMetres(p.max_error_m)} off line ${p.line + 1} for ${formatDuration(p.duration_s)}`)
        .addTo(group);
    }
    if (run.last_fix) {
      L.marker([run.last_fix.lat, run.last_fix.lon], {
        pmIgnore: true,
        interactive: false,
        title: "Tractor",
        alt: "Tractor's last position",
        icon: L.divIcon({ className: "tractor-marker", html: "<span></span>", iconSize: [22, 22], iconAnchor: [11, 11] }),
      }).addTo(group);
    }
    state.runLayer = group.addTo(map);
    const title = run.name || `Run ${run.id}`;
    ui.runTitle.textContent = `(${title}, ${run.source === "live" ? "live" : run.source.toUpperCase()})`;
    fillFigures(ui.run, run.metrics, {
      fixes: String(run.fix_count),
      stretches: stretchesText(run.metrics),
    });
    ui.runGpx.href = api.runGpxUrl(run.id);
    ui.runGpx.hidden = run.fix_count === 0;
    ui.runKml.href = api.runKmlUrl(run.id);
    ui.runKml.hidden = run.fix_count === 0;
    ui.run.hidden = false;
    stopPolling();
    if (run.source === "live") {
      state.timer = setTimeout(() => pollRun(run.id), LIVE_POLL_MS);
    }
  }

  async function pollRun(id) {
    if (state.runId !== id) return;
    try {
      // Only what is new since the last fix drawn: fast however long the run (issue 15).
      const since = state.run?.id === id ? state.run.last_fix?.t : undefined;
      const update = await api.readRun(id, since);
      if (state.runId === id) showRun(since ? withNewFixes(state.run, update) : update);
    } catch (error) {
      // A lost connection in the field is normal: try again on the next tick.
      if (state.runId === id) state.timer = setTimeout(() => pollRun(id), LIVE_POLL_MS);
      if (error?.status === 404) stopPolling();
    }
  }

  /** The run read before with the newer fixes of `update` appended to its track. */
  function withNewFixes(run, update) {
    if (!update.track) return { ...update, track: run.track };
    if (!run.track) return update;
    const coordinates = [...run.track.geometry.coordinates, ...update.track.geometry.coordinates];
    const time_s = [...(run.track.properties.time_s || []), ...(update.track.properties.time_s || [])];
    return {
      ...update,
      track: { ...run.track, properties: { ...run.track.properties, time_s }, geometry: { ...run.track.geometry, coordinates } },
    };
  }

  function runItem(run) {
    const item = document.createElement("li");
    item.dataset.id = String(run.id);
    const open = document.createElement("button");
    open.type = "button";
    open.className = "open-plan";
    const title = run.name || `Run ${run.id}`;
    open.setAttribute("aria-label", `Open run ${title}`);
    const name = document.createElement("span");
    name.className = "plan-name";
    name.textContent = title;
    const meta = document.createElement("span");
    meta.className = "plan-meta";
    meta.textContent = [formatDate(run.created_at), run.source === "live" ? "live" : run.source.toUpperCase(), `${run.fix_count} fixes`]
      .filter(Boolean)
      .join(" · ");
    open.append(name, meta);
    open.addEventListener("click", () => openRun(run.id));
    item.append(open);
    return item;
  }

  async function refreshRuns() {
    const planId = state.planId;
    if (planId == null) {
      ui.runs.replaceChildren();
      ui.runsEmpty.hidden = false;
      return;
    }
    try {
      const { items } = await api.listRuns(planId);
      if (planId !== state.planId) return;
      ui.runs.replaceChildren(...items.map(runItem));
      ui.runsEmpty.hidden = items.length > 0;
    } catch (error) {
      showFailure(error);
    }
  }

  async function openRun(id) {
    clearError();
    try {
      showRun(await api.readRun(id));
    } catch (error) {
      showFailure(error);
    }
  }

  async function simulate() {
    const planId = state.planId;
    if (planId == null) return;
    clearError();
    const seq = ++state.seq;
    ui.simulate.disabled = true;
    ui.card.setAttribute("aria-busy", "true");
    setStatus("Simulating the tractor…");
    try {
      const body = {
        seed: Math.floor(Math.random() * 1_000_000),
        gps: ui.gps.value,
        guidance: ui.guidance.value,
      };
      const simulation = await api.simulate(planId, body);
      if (seq !== state.seq || planId !== state.planId) return;
      showSimulation(simulation);
      setStatus(`Simulated run: ${formatDuration(simulation.metrics.time_s)}.`);
    } catch (error) {
      if (seq === state.seq) {
        setStatus("");
        showFailure(error);
      }
    } finally {
      ui.card.setAttribute("aria-busy", "false");
      setEnabled();
    }
  }

  async function upload(file) {
    const planId = state.planId;
    if (planId == null) return;
    clearError();
    ui.upload.disabled = true;
    ui.card.setAttribute("aria-busy", "true");
    setStatus(`Uploading ${file.name}…`);
    try {
      const run = await api.uploadRun(planId, file);
      if (planId !== state.planId) return;
      showRun(run);
      setStatus(`Uploaded ${file.name}: ${run.fix_count} fixes.`);
      await refreshRuns();
    } catch (error) {
      setStatus("");
      showFailure(error);
    } finally {
      ui.card.setAttribute("aria-busy", "false");
      setEnabled();
    }
  }

  ui.simulate.addEventListener("click", simulate);
  ui.upload.addEventListener("click", () => ui.file.click());
  ui.file.addEventListener("change", () => {
    const [file] = ui.file.files;
    ui.file.value = "";
    if (file) upload(file);
  });

  return {
    /** The plan on the map changed: `planId` if it is stored, else null. */
    planChanged(planId) {
      if (planId === state.planId) return;
      state.planId = planId;
      state.seq += 1;
      clearSimulation();
      clearRun();
      setEnabled();
      refreshRuns();
    },
  };
}
