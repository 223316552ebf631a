// The page's side of a student's run: the Python worker, the memory it shares with the page, and the robot's
// drive and telemetry channels. The worker's commands reach the robot only through the drive socket (DriveSession:
// sequence numbers, 20 Hz repeats the deadman expects, a stop on release), so the server checks each one as it
// checks the pad's. If the worker stops ticking (a loop without robot.tick(), a crash), the page stops the robot
// within WATCHDOG_MS; a closed tab closes the socket, and the server (and else the robot's deadman) stops it.
import { Channel, fetchJson, parseJsonMessage } from "../../lib/transport.js";
import { DriveSession } from "../../lib/drive-session.js";
import { t } from "../../lib/i18n.js";

const STOP = 0, TELEMETRY_VERSION = 1, SKILL_STATE = 2, SKILL_RESULT = 3, TELEMETRY_BYTES = 4;
const TELEMETRY_CAPACITY = 64 * 1024;
export const WATCHDOG_MS = 300;  // no tick for this long: the page stops the robot
const STOP_GRACE_MS = 1500;  // an interrupt not answered in this time: the worker is replaced
const SKILL_POLL_MS = 250;
const FINAL_GOAL = { succeeded: 1, aborted: 2, canceled: 3 };
const EXECUTING = 5;  // a skill started without waiting for its end (python-worker.js's SKILL_STATUSES)

/** The Python worker with its shared memory; "ready" resolves when Pyodide has loaded (load_s in the detail). */
export class PythonWorker extends EventTarget {
  constructor() {
    super();
    this.control = new Int32Array(new SharedArrayBuffer(8 * 4));
    this.telemetry = new Uint8Array(new SharedArrayBuffer(TELEMETRY_CAPACITY));
    this.interrupt = new Uint8Array(new SharedArrayBuffer(1));
    this.ready = this.#spawn();
  }

  #spawn() {
    this.worker?.terminate();
    this.worker = new Worker("/exercises/python-worker.js", { type: "module" });
    return new Promise((resolve, reject) => {
      this.worker.onmessage = (event) => {
        const message = event.data;
        if (message.type === "ready") resolve(message);
        else if (message.type === "failed" && !this.loaded) reject(new Error(message.message));
        this.dispatchEvent(new CustomEvent("message", { detail: message }));
      };
      this.worker.onerror = (event) => reject(new Error(event.message || t("The Python worker did not start.")));
      this.worker.postMessage({ type: "init", control: this.control.buffer, telemetry: this.telemetry.buffer,
                                interrupt: this.interrupt.buffer });
    }).then((message) => { this.loaded = true; return message; });
  }

  /** Replace a worker that does not answer (the interpreter reloads; "restarting" says so, with the new ready). */
  restart() {
    this.loaded = false;
    this.ready = this.#spawn();
    this.dispatchEvent(new CustomEvent("restarting", { detail: this.ready }));
    return this.ready;
  }

  writeTelemetry(text) {
    const bytes = new TextEncoder().encode(text);
    if (bytes.length > this.telemetry.length) return;
    Atomics.add(this.control, TELEMETRY_VERSION, 1);  // odd: being written
    this.telemetry.set(bytes);
    Atomics.store(this.control, TELEMETRY_BYTES, bytes.length);
    Atomics.add(this.control, TELEMETRY_VERSION, 1);
  }

  run(code, limits) {
    Atomics.store(this.control, STOP, 0);
    Atomics.store(this.control, SKILL_STATE, 0);
    this.interrupt[0] = 0;
    this.worker.postMessage({ type: "run", code, ...limits });
  }

  stop() {
    Atomics.store(this.control, STOP, 1);
    Atomics.notify(this.control, STOP);
    this.interrupt[0] = 2;  // SIGINT: a KeyboardInterrupt at the interpreter's next check
  }

  skillEnded(code) {
    Atomics.store(this.control, SKILL_RESULT, code);
    Atomics.store(this.control, SKILL_STATE, 2);
    Atomics.notify(this.control, SKILL_STATE);
  }
}

/**
 * One run of the student's code on a robot. Events: "print" (detail: {line, stream}), "state" (detail: text),
 * "sent" (a drive command went), "ack" (detail: the ack, with performance.now() of its command in sent_at),
 * "done" (detail: the worker's outcome plus the report, if the code made one, and refused: why the robot stopped
 * taking the run's commands, if it did).
 */
export class RobotRun extends EventTarget {
  #python; #robotName; #drive; #telemetry; #localization; #located = null; #session; #watchdog = 0; #lastTick = 0; #skillPending = false;
  #finished = false; #stopTimer = 0; #report = null; #refused = null; #command = { linear_mps: 0, angular_radps: 0 };
  #sentAt = new Map();
  #codeAt = null;

  constructor(python, robotName) {
    super();
    this.#python = python;
    this.#robotName = robotName;
    this.onWorker = (event) => this.#fromWorker(event.detail);
  }

  /** Opens the robot's channels; resolves with the drive socket's ready message (limits, is_controller) once the
   * first telemetry has come too (the program's first tick reads real sensors). */
  connect() {
    const path = `/ws/robots/${encodeURIComponent(this.#robotName)}`;
    this.#drive = new Channel(`${path}/drive`);
    this.#session = new DriveSession(this.#drive);
    this.#telemetry = new Channel(`${path}/telemetry`);
    this.#telemetry.addEventListener("message", (event) => {
      if (typeof event.detail !== "string") return;
      const message = parseJsonMessage(event.detail);
      if (message?.type !== "telemetry") return;
      // What the program reads: the robot's readings and the localization estimate, never where it truly stands.
      this.#python.writeTelemetry(JSON.stringify({ ...message, camera_pose: null, localization: this.#located }));
      this.dispatchEvent(new CustomEvent("telemetry", { detail: message }));
    });
    this.#localization = new Channel(`${path}/localization`);
    this.#localization.addEventListener("message", (event) => {
      const message = typeof event.detail === "string" ? parseJsonMessage(event.detail) : null;
      if (message?.type !== "localization") return;
      this.#located = message.active ? { converged: message.converged, estimate: message.estimate,
        std_x_m: message.std_x_m, std_y_m: message.std_y_m, std_theta_rad: message.std_theta_rad,
        sim_time_s: message.sim_time_s } : null;
    });
    this.#session.addEventListener("error", (event) => {
      // The command path refuses a user who no longer controls the robot (a lab robot's turn moved on): the run ends.
      if (event.detail.code === "not_controller") this.endRefused(event.detail.message);
      else this.#print(t("Robot: {message}", { message: event.detail.message }), "stderr");
    });
    this.#session.addEventListener("sent", (event) => {
      this.#sentAt.set(event.detail.sequence, { page: performance.now(), code: this.#codeAt });
      this.dispatchEvent(new CustomEvent("sent", { detail: event.detail }));
    });
    this.#session.addEventListener("ack", (event) => {
      const sent = this.#sentAt.get(event.detail.sequence);
      this.#sentAt.delete(event.detail.sequence);
      if (this.#sentAt.size > 200) this.#sentAt.clear();
      this.dispatchEvent(new CustomEvent("ack", { detail: { ...event.detail, sent_at: sent?.page, code_at: sent?.code } }));
    });
    const heard = new Promise((resolve) => this.addEventListener("telemetry", resolve, { once: true }));
    const ready = new Promise((resolve) => this.#session.addEventListener("ready", (event) => resolve(event.detail),
                                                                           { once: true }));
    return Promise.all([ready, heard]).then(([message]) => message);
  }

  /** Runs the code once the interpreter is loaded (a worker replaced after a Stop may still be loading). */
  async start(code, limits) {
    await this.#python.ready;
    if (this.#finished) return;
    this.#python.addEventListener("message", this.onWorker);
    this.#lastTick = performance.now();
    this.#watchdog = setInterval(() => this.#checkTicks(), 50);
    this.#python.run(code, limits);
  }

  /** Stop: the interpreter is interrupted, the robot stopped now; a worker that does not answer is replaced. */
  stop() {
    if (this.#finished) return;
    this.#session?.stop();
    this.#python.stop();
    clearTimeout(this.#stopTimer);
    this.#stopTimer = setTimeout(() => {
      if (this.#finished) return;
      this.#print(t("The program did not stop by itself: Python is restarted."), "stderr");
      this.#python.restart();
      this.#end({ ok: false, stopped: true, message: t("Stopped.") });
    }, STOP_GRACE_MS);
  }

  /** The robot takes no more of this run's commands (message: why): the program is stopped and the run ends, saying
   * so, at once rather than at its time limit. */
  endRefused(message) {
    if (this.#finished || this.#refused) return;
    this.#refused = message;
    this.stop();
  }

  /** Closes the channels (the server stops the robot when its drive socket closes). */
  close() {
    this.#session?.stop();
    this.#drive?.close();
    this.#telemetry?.close();
    this.#localization?.close();
    clearInterval(this.#watchdog);
  }

  #checkTicks() {
    if (this.#skillPending || this.#finished) return;
    if (performance.now() - this.#lastTick > WATCHDOG_MS && (this.#command.linear_mps || this.#command.angular_radps)) {
      this.#command = { linear_mps: 0, angular_radps: 0 };
      this.#session.stop();
      this.dispatchEvent(new CustomEvent("state", { detail: "watchdog" }));
    }
  }

  #fromWorker(message) {
    if (message.type === "drive") {
      this.#lastTick = performance.now();
      this.dispatchEvent(new CustomEvent("tick", { detail: { at: message.at } }));
      const same = message.linear_mps === this.#command.linear_mps && message.angular_radps === this.#command.angular_radps;
      if (!same) {
        this.#command = { linear_mps: message.linear_mps, angular_radps: message.angular_radps };
        this.#codeAt = message.at;  // the command this tick's code set (repeats carry none)
        this.#session.setCommand(this.#command);
        this.#codeAt = null;
      }
    } else if (message.type === "print") {
      this.#print(message.line, message.stream);
    } else if (message.type === "report") {
      this.#report = { x_m: message.x_m, y_m: message.y_m, t_s: message.t_s };
    } else if (message.type === "skill") {
      this.#runSkill(message.name, message.parameters, message.wait !== false);
    } else if (message.type === "done") {
      this.#end(message);
    }
  }

  async #runSkill(name, parameters, wait) {
    this.#skillPending = true;
    try {
      // The run's own robot: the practice robot, or the lab robot the run is on.
      const robot = encodeURIComponent(this.#robotName);
      const answer = await fetchJson(`/api/robots/${robot}/skills/${encodeURIComponent(name)}/goals`, { method: "POST",
        body: { parameters, preempt: true } });
      const goalId = answer.goal?.goal_id;
      let status = answer.goal?.status;
      if (!wait && goalId && !(status in FINAL_GOAL)) {
        this.#python.skillEnded(EXECUTING);
        return;
      }
      while (goalId && !(status in FINAL_GOAL) && !this.#finished) {
        await new Promise((resolve) => setTimeout(resolve, SKILL_POLL_MS));
        const goal = await fetchJson(`/api/robots/${robot}/goals/${encodeURIComponent(goalId)}`);
        status = goal.goal?.status ?? goal.status;
      }
      this.#python.skillEnded(FINAL_GOAL[status] ?? 2);
    } catch (error) {
      if (error.code === "not_controller") this.endRefused(error.message);
      else this.#print(t("Skill {name}: {message}", { name, message: error.message }), "stderr");
      this.#python.skillEnded(4);
    } finally {
      this.#skillPending = false;
      this.#lastTick = performance.now();
    }
  }

  #print(line, stream = "stdout") {
    this.dispatchEvent(new CustomEvent("print", { detail: { line, stream } }));
  }

  #end(outcome) {
    if (this.#finished) return;
    this.#finished = true;
    clearTimeout(this.#stopTimer);
    clearInterval(this.#watchdog);
    this.#python.removeEventListener("message", this.onWorker);
    this.#session?.stop();
    this.dispatchEvent(new CustomEvent("done", { detail: { ...outcome, report: this.#report, refused: this.#refused } }));
  }
}
