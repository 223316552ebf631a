// Response times as the 2003 paper's table 1 measures them, kept pure (times are passed in, never read here):
// each timed command (a skill activation, a drive command) has two legs, browser -> middleware and middleware ->
// skill server, summed into its total; each leg is summarised by minimum, maximum, mean and jitter, the
// inter-quartile range of its round trips (the paper's section 2.3, after Cottrell). The connection's throughput
// and its late and lost messages are the paper's bandwidth and packet-loss measures.

import { legFigures } from "./stats.js";
import { fixed, t } from "./i18n.js";

export const LATE_AFTER_MS = 1000; // the paper's reference for operability: a command answered later is late
export const LOST_AFTER_MS = 5000; // a command unanswered this long (or when its socket closed) is lost
export const KINDS = ["skill", "drive"];
export const LEGS = ["total", "client", "robot"];

/** One timed command: the browser's whole round trip and the middleware's call to the robot within it. */
export function timedSample(kind, sentMs, answeredMs, robotMs) {
  const total = answeredMs - sentMs;
  const robot = Number.isFinite(robotMs) && robotMs >= 0 ? Math.min(robotMs, total) : NaN;
  return { kind, at_ms: answeredMs, total_ms: total, robot_ms: robot,
    client_ms: Number.isFinite(robot) ? total - robot : NaN };
}

/** Commands sent and answered over one console's connections: samples, delivery counts and bytes moved. */
export class TimingLog {
  #pending = new Map(); // "kind:id" -> {kind, sentMs, bytes}
  #samples = { skill: [], drive: [] };
  #moved = []; // [{atMs, bytes}] for the throughput window
  #counts = { sent: 0, answered: 0, late: 0, lost: 0 };
  #cap;

  constructor({ cap = 5000 } = {}) {
    this.#cap = cap;
  }

  /** A command of kind left the browser at sentMs, bytes long. */
  sent(kind, id, sentMs, bytes = 0) {
    this.#pending.set(`${kind}:${id}`, { kind, sentMs, bytes });
    this.#counts.sent += 1;
    this.#moved.push({ atMs: sentMs, bytes });
  }

  /** Its answer came at answeredMs; robotMs is the middleware's own call to the robot. The sample, or null for an
   *  answer to nothing pending (a repeat, or one already counted lost). */
  answered(kind, id, answeredMs, { robotMs = NaN, bytes = 0, timed = true } = {}) {
    const key = `${kind}:${id}`;
    const pending = this.#pending.get(key);
    if (!pending) return null;
    this.#pending.delete(key);
    this.#counts.answered += 1;
    this.#moved.push({ atMs: answeredMs, bytes });
    if (answeredMs - pending.sentMs > LATE_AFTER_MS) this.#counts.late += 1;
    if (!timed) return null;
    const sample = timedSample(kind, pending.sentMs, answeredMs, robotMs);
    const series = this.#samples[kind];
    series.push(sample);
    if (series.length > this.#cap) series.shift();
    return sample;
  }

  /** The oldest pending command of kind was answered (an answer that names no command, on an ordered socket). */
  answeredOldest(kind, answeredMs, options = {}) {
    let oldest = null;
    for (const [key, pending] of this.#pending) {
      if (pending.kind === kind && (!oldest || pending.sentMs < oldest.sentMs)) oldest = { key, ...pending };
    }
    if (oldest) this.answered(kind, oldest.key.slice(kind.length + 1), answeredMs, { ...options, timed: false });
  }

  /** The server sent only the newest of the commands of kind waiting before id (a busy robot or worker): those
   *  before it were answered, by being superseded, not lost. Untimed: no answer of their own came. */
  supersededBefore(kind, id, answeredMs) {
    for (const [key, pending] of this.#pending) {
      if (pending.kind === kind && Number(key.slice(kind.length + 1)) < Number(id)) {
        this.answered(kind, key.slice(kind.length + 1), answeredMs, { timed: false });
      }
    }
  }

  /** A command of kind never reached its answer (the network failed under it). */
  lost(kind, id) {
    if (this.#pending.delete(`${kind}:${id}`)) this.#counts.lost += 1;
  }

  /** Counts as lost what waited LOST_AFTER_MS by nowMs, or every pending command of kind (its socket closed). */
  expire(nowMs, kind = null) {
    for (const [key, pending] of this.#pending) {
      if ((kind && pending.kind === kind) || nowMs - pending.sentMs >= LOST_AFTER_MS) {
        this.#pending.delete(key);
        this.#counts.lost += 1;
      }
    }
  }

  /** The samples of kind, oldest first (at most cap). */
  samples(kind) {
    return this.#samples[kind].slice();
  }

  /** {total, client, robot} figures of kind's samples. */
  figures(kind) {
    const series = this.#samples[kind];
    return Object.fromEntries(LEGS.map((leg) => [leg, legFigures(series.map((sample) => sample[`${leg}_ms`]))]));
  }

  /** {sent, answered, late, lost, waiting}. */
  delivery() {
    return { ...this.#counts, waiting: this.#pending.size };
  }

  /** Bytes per second moved (requests and answers) over the windowMs before nowMs. */
  throughput(nowMs, windowMs = 10000) {
    this.#moved = this.#moved.filter((entry) => nowMs - entry.atMs <= windowMs);
    return this.#moved.reduce((sum, entry) => sum + entry.bytes, 0) / (windowMs / 1000);
  }
}

const REPORTED_FIGURES = ["min", "mean", "max", "jitter"];

/** What the console reports of log for the tutor's class view: per kind its count and each leg's figures (null for
 *  none), the delivery counts and the throughput over the windowMs before nowMs. */
export function reportOf(log, nowMs, windowMs = 10000) {
  const report = {};
  for (const kind of KINDS) {
    const figures = log.figures(kind);
    report[kind] = { count: figures.total.count };
    for (const leg of LEGS) {
      report[kind][leg] = Object.fromEntries(REPORTED_FIGURES.map((name) => [name,
        Number.isFinite(figures[leg][name]) ? figures[leg][name] : null])); // unrounded: shown as the panel shows it
    }
  }
  const { sent, late, lost } = log.delivery();
  return { ...report, delivery: { sent, late, lost }, throughput_bps: log.throughput(nowMs, windowMs) };
}

const KIND_WORDS = { skill: t("skill activations"), drive: t("drive commands") };

/** One line a tutor reads for a reported kind: "3 skill activations: 80.9–196.2 ms, mean 128.4, jitter 57.7", or
 *  "no skill activations" when none was timed. Pure. */
export function reportLine(report, kind) {
  const timed = report?.[kind];
  const total = timed?.total;
  if (!timed?.count || !Number.isFinite(total?.mean)) return t("no {value}", { value: KIND_WORDS[kind] });
  const ms = (value) => (Number.isFinite(value) ? fixed(value, 1) : "—");
  return t("{count} {value}: {min}–{max} ms, mean {mean}, ", { count: timed.count, value: KIND_WORDS[kind], min: ms(total.min), max: ms(total.max), mean: ms(total.mean) })
    + t("jitter {jitter}", { jitter: ms(total.jitter) });
}
