// A short two-note tone for "your turn has started", for someone looking at another window. Browsers
// allow sound only after the person interacted with the page; without it the flash alone tells them.

let context = null;

/** Plays the tone once; silently does nothing where audio is not allowed or not available. */
export function playTurnTone() {
  try {
    context ??= new AudioContext();
    if (context.state === "suspended") context.resume().catch(() => {});
    const start = context.currentTime;
    [660, 880].forEach((frequency, index) => {
      const oscillator = context.createOscillator();
      const gain = context.createGain();
      oscillator.frequency.value = frequency;
      gain.gain.setValueAtTime(0.08, start + index * 0.16);
      gain.gain.exponentialRampToValueAtTime(0.0001, start + index * 0.16 + 0.15);
      oscillator.connect(gain).connect(context.destination);
      oscillator.start(start + index * 0.16);
      oscillator.stop(start + index * 0.16 + 0.16);
    });
  } catch {
    // no audio here: the visible notice stands alone
  }
}
