// Background jobs on the map page (product.md §13): follow a job the server runs for us, show
// how far it has got in a progress bar with a Cancel button, and hand back what it produced.
// The page never waits on a request for long work: it asks, gets a job, and polls it.

import { t } from "./i18n.js";

/** How often a running job is asked for its progress [ms]. */
export const JOB_POLL_MS = 400;

/** The job was cancelled (by this page or another): not an error to show. */
export class JobCancelled extends Error {
  constructor(job) {
    super("cancelled");
    this.name = "JobCancelled";
    this.job = job;
  }
}

/** The job failed: its message names the input and the problem, as an API error does. */
export class JobFailed extends Error {
  constructor(job) {
    super(job.error || t("The job failed."));
    this.name = "JobFailed";
    this.job = job;
  }
}

const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

/**
 * Poll a job until it is done; answer the finished job.
 *
 * @param {{readJob: (id: number) => Promise<object>}} api
 * @param {object} job the job as the server answered 202
 * @param {object} options
 * @param {(job: object) => void} [options.onProgress] called with each answer
 * @param {() => boolean} [options.stillWanted] polling stops quietly (answer null) when false
 * @returns {Promise<object | null>}
 * @throws {JobFailed | JobCancelled}
 */
export async function followJob(api, job, { onProgress = () => {}, stillWanted = () => true } = {}) {
  let current = job;
  for (;;) {
    onProgress(current);
    if (current.status === "done") return current;
    if (current.status === "failed") throw new JobFailed(current);
    if (current.status === "cancelled") throw new JobCancelled(current);
    await sleep(JOB_POLL_MS);
    if (!stillWanted()) return null;
    try {
      current = await api.readJob(current.id);
    } catch (error) {
      // A lost connection is not the job's end: ask again on the next tick.
      if (error?.status !== 0) throw error;
    }
  }
}

/**
 * A progress bar with a label and a Cancel button for one job at a time.
 *
 * @param {object} elements
 * @param {HTMLElement} elements.box shown while a job runs
 * @param {HTMLProgressElement} elements.bar
 * @param {HTMLElement} elements.label
 * @param {HTMLButtonElement} elements.cancel
 * @param {(id: number) => Promise<unknown>} cancelJob
 */
export function jobProgress({ box, bar, label, cancel }, cancelJob) {
  let jobId = null;
  cancel.addEventListener("click", async () => {
    if (jobId == null) return;
    cancel.disabled = true;
    label.textContent = t("Cancelling…");
    try {
      await cancelJob(jobId);
    } catch {
      // Already finished: the next poll tells.
    }
  });
  return {
    /** Show `job`'s state (`what` names the work: "Simulating 200 runs"). */
    show(job, what) {
      jobId = job.id;
      box.hidden = false;
      cancel.disabled = job.status !== "queued" && job.status !== "running";
      bar.value = job.progress;
      const percent = Math.floor(job.progress * 100);
      label.textContent =
        job.status === "queued"
          ? t("{what}: waiting for a worker…", { what })
          : t("{what}: {percent} %", { what, percent: String(percent) });
    },
    hide() {
      jobId = null;
      box.hidden = true;
    },
  };
}
