// The fully guided tour's step engine: a pure state machine with its effects injected, so it runs the
// same against the practice robot and against fakes in a test.
//
// Each step: show it (text, panel to look at), run its command if any, then wait for its condition:
// "skill_finished" (the goal ends), "time" (seconds pass), or "manual" (the learner presses Next).
// Pause stops the robot and the wait; resume replays the current step; replay starts from step 0.

import { t } from "../../lib/i18n.js";


export class TourEngine {
  /**
   * steps: [{text, panel, command, condition: {type, seconds}}]
   * io: { show(index, step), run(index) -> Promise<goalId|null>, waitGoal(goalId, signal) -> Promise<status>,
   *       sleep(ms, signal) -> Promise, stop() -> Promise, changed(state) }
   */
  constructor(steps, io) {
    this.steps = steps;
    this.io = io;
    this.index = 0;
    this.status = "ready";  // ready | running | waiting | paused | done | failed
    this.message = "";
    this.epoch = 0;         // every pause/replay starts a new epoch; stale continuations see a newer one
    this.controller = null;
  }

  get state() {
    return { index: this.index, status: this.status, message: this.message, count: this.steps.length };
  }

  _set(status, message = "") {
    this.status = status;
    this.message = message;
    this.io.changed(this.state);
  }

  start() {
    return this._runFrom(0);
  }

  replay() {
    return this._runFrom(0);
  }

  resume() {
    if (this.status !== "paused") return Promise.resolve();
    return this._runFrom(this.index);
  }

  /** The learner moves on from a manual step (or skips the wait). */
  next() {
    if (this.status === "done" || this.status === "paused") return Promise.resolve();
    return this._runFrom(this.index + 1);
  }

  async pause() {
    if (this.status === "done" || this.status === "ready") return;
    this.epoch += 1;
    this.controller?.abort();
    this._set("paused", t("Paused. Resume replays this step."));
    await this.io.stop();
  }

  async _runFrom(index) {
    const epoch = ++this.epoch;
    this.controller?.abort();
    const controller = new AbortController();
    this.controller = controller;
    for (let i = index; i < this.steps.length; i += 1) {
      if (epoch !== this.epoch) return;
      this.index = i;
      const step = this.steps[i];
      this.io.show(i, step);
      this._set("running");
      let goalId = null;
      try {
        if (step.command) goalId = await this.io.run(i);
        if (epoch !== this.epoch) return;
        this._set("waiting");
        const condition = step.condition ?? { type: "manual" };
        if (condition.type === "time") {
          await this.io.sleep(condition.seconds * 1000, controller.signal);
        } else if (condition.type === "skill_finished" && goalId) {
          const status = await this.io.waitGoal(goalId, controller.signal);
          if (epoch !== this.epoch) return;
          if (status !== "succeeded") this.message = t("The skill ended {status}; the tour goes on.", { status });
        } else {
          return;  // manual: next() continues
        }
      } catch (error) {
        if (epoch !== this.epoch || error?.name === "AbortError") return;
        this._set("failed", error?.message ?? String(error));
        return;
      }
    }
    if (epoch === this.epoch) this._set("done", t("The tour is over. Replay it, or try the steps yourself."));
  }
}

/** A sleep that rejects with AbortError when signal aborts. */
export function abortableSleep(ms, signal) {
  return new Promise((resolve, reject) => {
    if (signal?.aborted) { reject(new DOMException("aborted", "AbortError")); return; }
    const timer = setTimeout(resolve, ms);
    signal?.addEventListener("abort", () => { clearTimeout(timer); reject(new DOMException("aborted", "AbortError")); },
      { once: true });
  });
}
