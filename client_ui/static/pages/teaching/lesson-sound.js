// A sound cue: the robot's speaker is the learner's browser. The tone plays through Web Audio and its caption
// stays visible at least CAPTION_MIN_S, so a learner who cannot hear it reads what the robot did.
const CAPTION_MIN_S = 4;
let audio = null;
let hideTimer = null;

/** Plays a sine tone of frequency_hz for duration_s (a short fade in and out, so it does not click). */
export function playTone({ frequency_hz: hz, duration_s: seconds }) {
  const Context = window.AudioContext || window.webkitAudioContext;
  if (!Context) return false;
  audio = audio || new Context();
  if (audio.state === "suspended") audio.resume();
  const start = audio.currentTime;
  const oscillator = audio.createOscillator();
  const gain = audio.createGain();
  oscillator.frequency.value = hz;
  gain.gain.setValueAtTime(0, start);
  gain.gain.linearRampToValueAtTime(0.25, start + 0.02);
  gain.gain.setValueAtTime(0.25, start + Math.max(0.02, seconds - 0.03));
  gain.gain.linearRampToValueAtTime(0, start + seconds);
  oscillator.connect(gain).connect(audio.destination);
  oscillator.start(start);
  oscillator.stop(start + seconds);
  return true;
}

/** Shows the sound's caption in element (a live region) for the sound's length, and at least CAPTION_MIN_S. */
export function showCaption(element, { caption, duration_s: seconds }) {
  element.textContent = `♪ ${caption}`;
  element.hidden = false;
  clearTimeout(hideTimer);
  hideTimer = setTimeout(() => { element.hidden = true; }, Math.max(CAPTION_MIN_S, seconds) * 1000);
}
