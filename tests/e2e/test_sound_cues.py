"""A lesson's sound cue in Chromium: when the video reaches it, the page plays the tone (Web Audio, the robot's
speaker in the browser) and shows its caption for those who cannot hear it, while the robot stands still.
Screenshot: lesson-sound-caption.png."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.conftest import ARTIFACTS_DIR, LiveServer
from tests.e2e.test_lessons import _wait_for, lesson_on_pattern, pattern_video, practice_robot_running  # noqa: F401

pytestmark = pytest.mark.e2e
TRACK = """WEBVTT

00:00:00.500 --> 00:00:02.500
{"sound": {"frequency_hz": 660, "duration_s": 0.8, "caption": "The robot beeps <twice>"}}
"""
# Counts every tone the page starts, with its pitch: the test hears through this, not a speaker.
AUDIO_SPY = """
window.__tones = [];
const original = AudioContext.prototype.createOscillator;
AudioContext.prototype.createOscillator = function () {
  const oscillator = original.call(this);
  const start = oscillator.start.bind(oscillator);
  oscillator.start = (when) => { window.__tones.push(oscillator.frequency.value); start(when); };
  return oscillator;
};
"""


def test_a_sound_cue_plays_its_tone_and_shows_its_caption(page, live_server: LiveServer,
                                                         pattern_video: Path) -> None:  # noqa: F811
    lesson_id = lesson_on_pattern(live_server, pattern_video, TRACK, "sound", "Sound")
    page.add_init_script(AUDIO_SPY)
    with practice_robot_running(page, live_server):
        page.goto(f"{live_server.url}/lessons/{lesson_id}")
        page.wait_for_selector("#lesson[data-ready=true]")
        caption = page.locator('[data-field="sound-caption"]')
        assert caption.is_hidden()
        page.evaluate("document.querySelector('video').muted = true")
        page.evaluate("document.querySelector('video').play()")
        _wait_for(page, "the robot plays a sound")
        caption.wait_for(state="visible")
        assert caption.text_content() == "♪ The robot beeps <twice>"
        assert caption.get_attribute("role") == "status"
        assert page.evaluate("window.__tones") == [660]
        page.screenshot(path=str(ARTIFACTS_DIR / "lesson-sound-caption.png"), full_page=True)
