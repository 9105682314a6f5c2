// Simulations and field runs on the map page (product.md §7, §8): the Simulate and Upload track
// buttons, the simulated or recorded track drawn over the plan, its metrics beside the Plan
// summary, and a live run that grows while the tractor's logger streams fixes. Every figure and
// every coordinate comes from the API.

/* global L */

import { formatDate, formatDuration, formatMetres, formatPercent } from "./format.js";
import { t, tn } from "./i18n.js";

/** How often a live run is fetched again [ms]. */
export const LIVE_POLL_MS = 3000;

const SIM_STYLE = { color: "#76ff03", weight: 3, opacity: 0.95 };
const RUN_STYLE = { color: "#ff4df0", weight: 3, opacity: 0.95 };
const OFF_LINE_STYLE = { color: "#ff2d2d", weight: 7, opacity: 0.85, lineCap: "round" };

const $ = (id) => document.getElementById(id);

/** "live", or the file format a run was uploaded in (GPX, CSV, NMEA). */
function sourceLabel(source) {
  return source === "live" ? t("live") : String(source).toUpperCase();
}

const GPS_LABELS = { m8n: "u-blox M8N", rtk: "RTK" };
const GUIDANCE_LABELS = { waypoint: t("waypoints"), line: t("line following") };

/** "(u-blox M8N, waypoints, seed 42)": how a simulation was run. */
function simulationLabel(config) {
  const { gps, guidance, seed } = config ?? {};
  return t("({gps}, {guidance}, seed {seed})", {
    gps: GPS_LABELS[gps] ?? String(gps),
    guidance: GUIDANCE_LABELS[guidance] ?? String(guidance),
    seed: String(seed),
  });
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
    completed: metrics ? (metrics.completed ? t("yes") : t("no")) : "–",
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
  if (n === 0) return t("never more than {threshold} off a line", { threshold: formatMetres(metrics.threshold_m) });
  const seconds = metrics.stretches.reduce((sum, s) => sum + s.duration_s, 0);
  return tn(
    "{count} stretch over {threshold}, {time} in all",
    "{count} stretches over {threshold}, {time} in all",
    n,
    { count: n, threshold: formatMetres(metrics.threshold_m), time: formatDuration(seconds) },
  );
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
export function setUpChecks({ map, api, setStatus, showFailure, clearError, onResult = setStatus }) {
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
  const state = { planId: null, simLayer: null, runLayer: null, runId: null, timer: null, seq: 0 };

  function setEnabled() {
    const enabled = state.planId != null;
    ui.simulate.disabled = !enabled;
    ui.upload.disabled = !enabled;
    ui.hint.textContent = enabled
      ? t("Upload the tractor's log: a GPX track, a CSV file (time,lat,lon) or a u-blox NMEA log.")
      : t("Save the plan first, then simulate it or upload the tractor's track.");
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
    ui.simulationTitle.textContent = simulationLabel(simulation.config);
    fillFigures(ui.simulation, simulation.metrics);
    ui.simulationGpx.href = api.simulationGpxUrl(simulation.id);
    ui.simulationKml.href = api.simulationKmlUrl(simulation.id);
    ui.simulation.hidden = false;
  }

  function showRun(run) {
    state.runLayer?.remove();
    state.runId = run.id;
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
        .bindTooltip(
          t("Up to {error} off line {line} for {time}", {
            error: formatMetres(p.max_error_m),
            line: String(p.line),
            time: formatDuration(p.duration_s),
          }),
        )
        .addTo(group);
    }
    if (run.last_fix) {
      L.marker([run.last_fix.lat, run.last_fix.lon], {
        pmIgnore: true,
        interactive: false,
        title: t("Tractor"),
        alt: t("Tractor's last position"),
        icon: L.divIcon({ className: "tractor-marker", html: "<span></span>", iconSize: [22, 22], iconAnchor: [11, 11] }),
      }).addTo(group);
    }
    state.runLayer = group.addTo(map);
    const title = run.name || t("Run {id}", { id: String(run.id) });
    ui.runTitle.textContent = `(${title}, ${sourceLabel(run.source)})`;
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
      const run = await api.readRun(id);
      if (state.runId === id) showRun(run);
    } catch (error) {
      // A lost connection in the field is normal: try again on the next tick.
      if (state.runId === id) state.timer = setTimeout(() => pollRun(id), LIVE_POLL_MS);
      if (error?.status === 404) stopPolling();
    }
  }

  function listItem({ id, title, meta, label, onOpen }) {
    const item = document.createElement("li");
    item.dataset.id = String(id);
    const open = document.createElement("button");
    open.type = "button";
    open.className = "open-plan";
    open.setAttribute("aria-label", label);
    const name = document.createElement("span");
    name.className = "plan-name";
    name.textContent = title;
    const details = document.createElement("span");
    details.className = "plan-meta";
    details.textContent = meta.filter(Boolean).join(" · ");
    open.append(name, details);
    open.addEventListener("click", onOpen);
    item.append(open);
    return item;
  }

  function runItem(run) {
    const title = run.name || t("Run {id}", { id: String(run.id) });
    return listItem({
      id: `run-${run.id}`,
      title,
      label: t("Open run {name}", { name: title }),
      meta: [formatDate(run.created_at), sourceLabel(run.source), tn("{count} fix", "{count} fixes", run.fix_count, { count: run.fix_count })],
      onOpen: () => openRun(run.id),
    });
  }

  function simulationItem(simulation) {
    const title = t("Simulation {id}", { id: String(simulation.id) });
    return listItem({
      id: `simulation-${simulation.id}`,
      title,
      label: t("Open simulation {name}", { name: title }),
      meta: [formatDate(simulation.created_at), simulationLabel(simulation.config), formatDuration(simulation.metrics?.time_s)],
      onOpen: () => openSimulation(simulation.id),
    });
  }

  async function refreshRuns() {
    const planId = state.planId;
    if (planId == null) {
      ui.runs.replaceChildren();
      ui.runsEmpty.hidden = false;
      return;
    }
    try {
      const [runs, simulations] = await Promise.all([api.listRuns(planId), api.listSimulations(planId)]);
      if (planId !== state.planId) return;
      const items = [
        ...simulations.items.map((s) => ({ at: s.created_at, node: simulationItem(s) })),
        ...runs.items.map((r) => ({ at: r.created_at, node: runItem(r) })),
      ].sort((a, b) => (a.at < b.at ? 1 : a.at > b.at ? -1 : 0));
      ui.runs.replaceChildren(...items.map((i) => i.node));
      ui.runsEmpty.hidden = items.length > 0;
    } catch (error) {
      showFailure(error);
    }
  }

  async function openSimulation(id) {
    clearError();
    try {
      showSimulation(await api.readSimulation(id));
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
    setStatus(t("Simulating the tractor…"), { sticky: true });
    try {
      const body = {
        seed: Math.floor(Math.random() * 1_000_000),
        gps: ui.gps.value,
        guidance: ui.guidance.value,
      };
      const simulation = await api.simulate(planId, body);
      if (seq !== state.seq || planId !== state.planId) return;
      showSimulation(simulation);
      onResult(t("Simulated run: {time}.", { time: formatDuration(simulation.metrics.time_s) }));
      refreshRuns();
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
    setStatus(t("Uploading {file}…", { file: file.name }), { sticky: true });
    try {
      const run = await api.uploadRun(planId, file);
      if (planId !== state.planId) return;
      showRun(run);
      onResult(tn("Uploaded {file}: {count} fix.", "Uploaded {file}: {count} fixes.", run.fix_count, { file: file.name, count: run.fix_count }));
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
