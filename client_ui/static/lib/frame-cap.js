// How often a view drawn in the browser may draw: on a small screen (a phone) at most SMALL_SCREEN_MAX_FPS frames a
// second, so the drawing spares the battery and leaves the main thread to the drive pad; elsewhere as often as the
// data comes. The views keep only the newest data while they wait, so a capped view is late by one gap at most and
// never works through a backlog.

export const SMALL_SCREEN_PX = 600;
export const SMALL_SCREEN_MAX_FPS = 15;

/** Whether the window is a small screen's (below SMALL_SCREEN_PX wide): fewer frames, and one pixel per CSS pixel. */
export function isSmallScreen() {
  return (window.innerWidth || 0) < SMALL_SCREEN_PX;
}

/** The frame rate a view may draw at now: SMALL_SCREEN_MAX_FPS on a small screen, else no cap (Infinity). */
export function maxFramesPerSecond() {
  return isSmallScreen() ? SMALL_SCREEN_MAX_FPS : Infinity;
}

/** Spaces a view's frames at least 1/fps apart; `fps` is asked each time (a phone turned sideways may pass 600 px). */
export class FrameCap {
  #fps;
  #lastMs = -Infinity;

  constructor(fps = maxFramesPerSecond) {
    this.#fps = fps;
  }

  /** Milliseconds until the next frame may be drawn (0: now). */
  waitMs(nowMs) {
    const fps = this.#fps();
    if (!(fps < Infinity)) return 0;
    return Math.max(0, this.#lastMs + 1000 / fps - nowMs);
  }

  /** A frame is being drawn at nowMs. */
  drawn(nowMs) {
    this.#lastMs = nowMs;
  }
}
