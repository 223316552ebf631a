// Runs the student's Python on Pyodide, in a worker so that no loop of theirs can freeze the page.
// The page and this worker share memory (the exercise page is cross-origin isolated): the page writes the robot's
// latest telemetry there and raises the stop flag; the interpreter's interrupt buffer turns Stop into a
// KeyboardInterrupt even inside `while True: pass`. Commands go to the page as messages; the page sends them to the
// robot through the drive socket (the one command path, with the deadman, the limits and every safety rule).
import { loadPyodide } from "/static/vendor/node_modules/pyodide/pyodide.mjs";

const PYODIDE_URL = "/static/vendor/node_modules/pyodide/";
const API_URL = "/static/pages/exercises/telelab.py";
// control (Int32Array) slots, shared with the page (exercise-run.js has the same numbers)
const STOP = 0, TELEMETRY_VERSION = 1, SKILL_STATE = 2, SKILL_RESULT = 3, TELEMETRY_BYTES = 4;
const SKILL_STATUSES = ["", "SUCCEEDED", "ABORTED", "CANCELED", "REFUSED", "EXECUTING"];

let pyodide = null;
let initialized = null;  // a run waits for it: a restarted worker may be asked to run before Pyodide has loaded
let control = null;
let telemetry = null;
let startedAt = 0;
let limits = [0.5, 1.5, 60];
const decoder = new TextDecoder();

function post(message) {
  self.postMessage(message);
}

const bridge = {
  now: () => (performance.now() - startedAt) / 1000,
  wait_until(tS) {
    for (;;) {
      if (Atomics.load(control, STOP)) return false;
      const leftMs = startedAt + tS * 1000 - performance.now();
      if (leftMs <= 0) return true;
      Atomics.wait(control, STOP, 0, Math.min(leftMs, 50));
    }
  },
  read() {
    for (let attempt = 0; attempt < 20; attempt += 1) {
      const before = Atomics.load(control, TELEMETRY_VERSION);
      if (before % 2 === 1) continue;
      const length = Atomics.load(control, TELEMETRY_BYTES);
      if (length === 0) return "{}";  // nothing heard from the robot yet
      const copy = telemetry.slice(0, length);  // TextDecoder does not read shared memory
      if (Atomics.load(control, TELEMETRY_VERSION) === before) return decoder.decode(copy);
    }
    return "{}";
  },
  send(linear, angular) {
    // at: when the code's command left the interpreter, on the clock the page shares (for the latency figures)
    post({ type: "drive", linear_mps: linear, angular_radps: angular, at: performance.timeOrigin + performance.now() });
  },
  skill(name, parametersJson, wait) {
    Atomics.store(control, SKILL_STATE, 1);
    post({ type: "skill", name, parameters: JSON.parse(parametersJson), wait: Boolean(wait) });
    while (Atomics.load(control, SKILL_STATE) === 1) {
      if (Atomics.load(control, STOP)) return "CANCELED";
      Atomics.wait(control, SKILL_STATE, 1, 50);
    }
    return SKILL_STATUSES[Atomics.load(control, SKILL_RESULT)] || "ABORTED";
  },
  report(x, y, t) {
    post({ type: "report", x_m: x, y_m: y, t_s: t });
  },
  limits: () => limits,
};

const RUNNER = `
import json, sys, traceback
import telelab, telelab_bridge

class PageBackend:
    def now(self): return telelab_bridge.now()
    def wait_until(self, t_s): return bool(telelab_bridge.wait_until(t_s))
    def read(self): return json.loads(telelab_bridge.read())
    def send(self, linear_mps, angular_radps): telelab_bridge.send(linear_mps, angular_radps)
    def skill(self, name, parameters, wait=True): return str(telelab_bridge.skill(name, json.dumps(parameters), wait))
    def report(self, x_m, y_m, t_s): telelab_bridge.report(x_m, y_m, t_s)
    def limits(self): return tuple(float(v) for v in telelab_bridge.limits())

def run_student(code):
    robot = telelab.attach(PageBackend())
    try:
        exec(compile(code, "exercise.py", "exec"), {"__name__": "__main__"})
        return json.dumps({"ok": True})
    except KeyboardInterrupt:
        return json.dumps({"ok": False, "stopped": True, "message": "Stopped."})
    except BaseException as error:
        frames = [f for f in traceback.extract_tb(error.__traceback__) if f.filename == "exercise.py"]
        if isinstance(error, SyntaxError) and error.filename == "exercise.py":
            line = error.lineno
        else:
            line = frames[-1].lineno if frames else None
        shown = traceback.format_exception(type(error), error, error.__traceback__)
        # Only the student's own frames: the API's and the runner's are noise to them.
        kept = [part for part in shown if "exercise.py" in part or not part.startswith("  File ")]
        return json.dumps({"ok": False, "line": line, "message": f"{type(error).__name__}: {error}",
                           "traceback": "".join(kept)})
    finally:
        robot.stop()
        telelab_bridge.send(0.0, 0.0)
`;

async function init(message) {
  control = new Int32Array(message.control);
  telemetry = new Uint8Array(message.telemetry);
  const began = performance.now();
  pyodide = await loadPyodide({ indexURL: PYODIDE_URL });
  pyodide.setInterruptBuffer(new Uint8Array(message.interrupt));
  pyodide.setStdout({ batched: (line) => post({ type: "print", line }) });
  pyodide.setStderr({ batched: (line) => post({ type: "print", line, stream: "stderr" }) });
  const api = await (await fetch(API_URL, { credentials: "same-origin" })).text();
  pyodide.FS.writeFile("/home/pyodide/telelab.py", api);
  pyodide.registerJsModule("telelab_bridge", bridge);
  pyodide.runPython("import sys\nsys.path.insert(0, '/home/pyodide')\n" + RUNNER);
  // The page says "Python <version>": the interpreter's (3.14.0), not Pyodide's own numbering (314.0.7).
  const version = String(pyodide.globals.get("sys").version).split(" ")[0];
  post({ type: "ready", load_s: (performance.now() - began) / 1000, version, pyodide_version: pyodide.version });
}

function run(message) {
  limits = [message.max_linear_mps, message.max_angular_radps, message.time_limit_s];
  startedAt = performance.now();
  const runStudent = pyodide.globals.get("run_student");
  let outcome;
  try {
    outcome = JSON.parse(runStudent(message.code));
  } catch (error) {
    outcome = { ok: false, message: String(error?.message ?? error) };
  } finally {
    runStudent?.destroy();
  }
  post({ type: "done", ...outcome });
}

self.onmessage = async (event) => {
  const message = event.data;
  try {
    if (message.type === "init") await (initialized = init(message));
    else if (message.type === "run") {
      await initialized;
      run(message);
    }
  } catch (error) {
    post({ type: "failed", message: String(error?.message ?? error) });
  }
};
