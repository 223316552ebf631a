// The video-to-robot rule of a lesson, as a small state machine with no DOM: the player feeds it the
// video's events and the text track's active cue; it answers which command to send. Tested on its own.
//
// The rule (the 2022 paper's, made exact):
//   entering a cue while playing sends its command;
//   leaving a cue with no next cue stops the robot (a cue is the span in which its command runs);
//   pause, seeking, buffering ("waiting") and the end stop the robot at once;
//   play (or "playing" after buffering) and a seek while playing resume the cue covering the position.

/** Reasons the robot is stopped. */
export const STOP_REASONS = Object.freeze(["pause", "seeking", "buffering", "end", "cue-exit"]);

/** The cue covering time t in a sorted list of {index, start_s, end_s}, or null (end is exclusive). */
export function cueAt(cues, t) {
  for (const cue of cues) {
    if (cue.start_s <= t && t < cue.end_s) return cue;
  }
  return null;
}

/** The cue index of a WebVTT cue id "cue-N", or null. */
export function cueIndexOf(id) {
  const match = /^cue-(\d{1,4})$/.exec(String(id ?? ""));
  return match ? Number(match[1]) : null;
}

export class CuePlayback {
  /** actions: { run(index, why), stop(why) } — called synchronously from the event handlers. */
  constructor(actions) {
    this.actions = actions;
    this.playing = false;   // the video is playing and not stalled
    this.seeking = false;
    this.active = null;     // index of the cue the text track says is active
    this.running = null;    // index whose command was sent and not stopped since
    this.stopped = true;    // the robot was told to stop (or never moved)
  }

  _stop(why) {
    this.running = null;
    this.stopped = true;
    this.actions.stop(why);
  }

  _resume(why) {
    if (this.active !== null) {
      if (this.running !== this.active) {
        this.running = this.active;
        this.stopped = false;
        this.actions.run(this.active, why);
      }
    } else if (!this.stopped) {
      this._stop("cue-exit");
    }
  }

  /** The text track's active cue changed (oncuechange); index or null. */
  cueChange(index) {
    this.active = index;
    if (this.playing && !this.seeking) this._resume("enter");
  }

  /** "play"/"playing": the video runs (again). */
  play() {
    this.playing = true;
    if (!this.seeking) this._resume("play");
  }

  pause() {
    this.playing = false;
    this._stop("pause");
  }

  /** "waiting": playback stalled for data. It goes on with "playing". */
  buffering() {
    this.playing = false;
    this._stop("buffering");
  }

  seekStart() {
    this.seeking = true;
    this._stop("seeking");
  }

  /** "seeked": paused tells whether the video stays paused; activeIndex is the cue at the new position. */
  seekEnd(paused, activeIndex) {
    this.seeking = false;
    this.active = activeIndex;
    this.playing = !paused;
    if (this.playing) this._resume("seek");
  }

  ended() {
    this.playing = false;
    this._stop("end");
  }
}

/** Running mean and count of a series of milliseconds. */
export function summarize(values) {
  const finite = values.filter((v) => Number.isFinite(v));
  if (!finite.length) return { count: 0, mean: null, max: null };
  const sum = finite.reduce((a, b) => a + b, 0);
  return { count: finite.length, mean: sum / finite.length, max: Math.max(...finite) };
}
