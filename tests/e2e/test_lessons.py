"""Video lessons in Chromium: the playback rule (play, pause, seek into and out of cues, buffering, end)
driving a real practice robot, and the pure playback module on its own."""

from __future__ import annotations

import math
import shutil
import subprocess
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from middleware.access.commands import owned_robot
from middleware.robots.messages import goal_dict
from protos.telelab.v1.robot_pb2 import Pose2D
from tests.conftest import ARTIFACTS_DIR, STUDENT_PASSWORD, LiveServer

pytestmark = pytest.mark.e2e
TRACK = """WEBVTT

00:00:01.000 --> 00:00:03.000
{"drive": {"linear_mps": 0.1, "angular_radps": 0}}

00:00:05.000 --> 00:00:08.000
{"skill": "go_to_goal", "parameters": {"goal_x_m": 0.3, "goal_y_m": 0.0, "speed_mps": 0.1}}
"""


def log_in(tab, live_server: LiveServer, username: str = "student1") -> None:
    tab.goto(f"{live_server.url}/login")
    tab.fill("#username", username)
    tab.fill("#password", STUDENT_PASSWORD)
    tab.get_by_role("button", name="Log in").click()
    tab.locator('[data-field="username"]').wait_for()


@pytest.fixture(scope="module")
def pattern_video(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 10 s test-pattern video made by ffmpeg, once for the module's lessons."""
    video = tmp_path_factory.mktemp("lesson-video") / "pattern.webm"
    subprocess.run(["ffmpeg", "-loglevel", "error", "-y", "-f", "lavfi", "-i", "testsrc=size=160x120:rate=10",
                    "-t", "10", "-c:v", "libvpx", "-b:v", "200k", str(video)], check=True)
    return video


@pytest.fixture
def lesson_id(live_server: LiveServer, pattern_video: Path) -> int:
    """A lesson on the test-pattern video, with two cues."""
    return lesson_on_pattern(live_server, pattern_video, TRACK, "pattern", "Pattern")


def lesson_on_pattern(live_server: LiveServer, pattern_video: Path, track: str, slug: str, title: str) -> int:
    """A lesson of the given cue track on the test-pattern video; its id."""
    from middleware.db import session_factory
    from middleware.teaching.cues import parse_cue_track
    from middleware.teaching.lessons import LessonDraft, save_lesson, video_dir

    folder = video_dir(live_server.app.instance_path)
    folder.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(pattern_video, folder / "pattern.webm")
    cues, errors = parse_cue_track(track, None)
    assert not errors
    with session_factory(live_server.app)() as session:
        lesson = save_lesson(session, LessonDraft(slug, title, "", "pattern.webm", cues), None)
        session.commit()
        return lesson.id


def _log(page) -> list[str]:
    """The page's robot log, oldest first, as 'kind: text without the time'."""
    items = page.eval_on_selector_all("[data-slot=log] li", "els => els.map(e => e.dataset.kind + ': ' + "
                                      "e.textContent.split(' · ')[1])")
    return list(reversed(items))


def _wait_for(page, text: str, timeout_ms: float = 15000) -> None:
    page.wait_for_function("t => [...document.querySelectorAll('[data-slot=log] li')].some(e => "
                           "e.textContent.includes(t))", arg=text, timeout=timeout_ms)


@contextmanager
def practice_robot_running(page, live_server: LiveServer) -> Iterator[object]:
    """student1 logged in with their practice robot started from its page (one at most); the farm's manager."""
    from middleware.teaching.practice_robots import practice_manager

    manager = practice_manager(live_server.app)
    manager.cap = 1
    try:
        log_in(page, live_server)
        page.goto(f"{live_server.url}/practice")
        page.get_by_role("button", name="Start my practice robot").click()
        page.wait_for_selector("#practice[data-running=true]", timeout=60000)
        yield manager
    finally:
        manager.shutdown()


def test_the_video_drives_the_practice_robot_by_the_exact_rule(page, live_server: LiveServer, lesson_id: int) -> None:
    with practice_robot_running(page, live_server) as manager:
        # Left away from its dock (issue 34, item 14): the lesson carries it back, where its video starts.
        practice = manager.get(_user_id(live_server, "student1"))
        _odometry, dock = practice.link.poses_now()
        owned_robot(practice.link, practice.token).place_robot(Pose2D(x_m=dock.x_m + 1.0, y_m=dock.y_m - 0.8,
                                                                      theta_rad=dock.theta_rad + 1.2))
        page.goto(f"{live_server.url}/lessons/{lesson_id}")
        page.wait_for_selector("#lesson[data-ready=true]")
        page.get_by_role("status").filter(has_text="Your practice robot is at its dock, where the lesson's video "
                                                   "starts.").wait_for(timeout=15_000)
        _odometry, standing = practice.link.poses_now()
        assert math.hypot(standing.x_m - dock.x_m, standing.y_m - dock.y_m) < 0.02, standing
        assert abs(math.remainder(standing.theta_rad - dock.theta_rad, math.tau)) < 0.02, standing
        camera = page.get_by_role("region", name="Camera", exact=True)
        camera.wait_for(timeout=30_000)
        assert page.get_by_role("region", name="Lab model", exact=True).is_visible()
        video_box, camera_box = page.locator("video").bounding_box(), camera.bounding_box()
        assert camera_box["x"] >= video_box["x"] + video_box["width"], "the camera is beside the video"
        video = "document.querySelector('video')"
        page.evaluate(f"{video}.muted = true")
        # play: entering cue 1 sends its command
        page.evaluate(f"{video}.play()")
        _wait_for(page, "cue 1 acknowledged")
        # pause inside the cue stops the robot at once
        page.evaluate(f"{video}.pause()")
        _wait_for(page, "stop (pause) acknowledged")
        drive_goal = page.get_attribute("#lesson", "data-last-goal")
        # seeking into cue 2 while paused stops (again) and sends nothing
        page.evaluate(f"{video}.currentTime = 5.5")
        _wait_for(page, "stop (seeking) acknowledged")
        assert not any(line.startswith("run: cue 2") for line in _log(page))
        # play resumes the command of the cue covering the position
        page.evaluate(f"{video}.play()")
        _wait_for(page, "cue 2 acknowledged")
        goal_id = page.get_attribute("#lesson", "data-last-goal")
        # seeking out of every cue while playing stops and resumes nothing
        page.evaluate(f"{video}.currentTime = 3.5")
        _wait_for(page, "stop (seeking) acknowledged")
        # buffering stops the robot ("waiting" is dispatched: a real stall cannot be made on a local file)
        page.evaluate(f"{video}.currentTime = 6.0")
        _wait_for(page, "cue 2 (seek)")
        page.evaluate(f"{video}.dispatchEvent(new Event('waiting'))")
        _wait_for(page, "stop (buffering) acknowledged")
        # the end stops the robot, and the lesson counts as watched (the tutors' usage page, xAPI "watched")
        with page.expect_response(lambda r: r.url.endswith(f"/api/lessons/{lesson_id}/watched"),
                                  timeout=20000) as watched:
            page.evaluate(f"{video}.currentTime = 9.5")
        assert watched.value.status == 200 and watched.value.json() == {"recorded": True}
        _wait_for(page, "stop (end) acknowledged", 20000)
        log = [line for line in _log(page) if not line.startswith("ack")]
        runs_and_stops = [line.split(" →")[0] for line in log]
        expected_order = ["run: cue 1 (", "stop: stop (pause)", "stop: stop (seeking)", "run: cue 2 (play)",
                          "stop: stop (seeking)", "run: cue 2 (seek)", "stop: stop (buffering)", "stop: stop (end)"]
        cursor = 0
        for expected in expected_order:
            cursor = next(i for i in range(cursor, len(runs_and_stops)) if runs_and_stops[i].startswith(expected))
        assert not any(line.startswith("error") for line in log), log
        # the robot really stopped: the cue's goals were preempted by the stops
        robot = manager.get(_user_id(live_server, "student1"))
        assert robot is not None
        for goal in (drive_goal, goal_id):
            assert goal_dict(robot.link.get_goal(goal))["status"] in {"canceled", "succeeded"}
        assert page.text_content("[data-latency=cueToAck]") != "–"
        assert page.text_content("[data-latency=pauseToAck]") != "–"
        ARTIFACTS_DIR.mkdir(exist_ok=True)
        page.screenshot(path=str(ARTIFACTS_DIR / "lesson-1280.png"), full_page=True)
        page.set_viewport_size({"width": 390, "height": 844})
        page.screenshot(path=str(ARTIFACTS_DIR / "lesson-390.png"), full_page=True)
        Path(ARTIFACTS_DIR / "lesson-latency.txt").write_text(
            "\n".join(f"{k}: {page.text_content(f'[data-latency={k}]')}"
                      for k in ("cueToAck", "middlewareToAck", "pauseDetect", "pauseToAck")))


def _user_id(live_server: LiveServer, name: str) -> int:
    from sqlalchemy import select

    from middleware.db import session_factory
    from middleware.models import User

    with session_factory(live_server.app)() as session:
        return session.scalar(select(User.id).where(User.username == name))


def test_the_pure_playback_rule(page, live_server: LiveServer) -> None:
    log_in(page, live_server)
    result = page.evaluate("""async () => {
      const m = await import('/static/pages/teaching/lesson-playback.js');
      const calls = [];
      const p = new m.CuePlayback({ run: (i, why) => calls.push(`run ${i} ${why}`),
                                    stop: (why) => calls.push(`stop ${why}`) });
      p.cueChange(1);            // paused: nothing
      p.play();                  // play inside cue 1
      p.play();                  // "playing" after "play": no second send
      p.cueChange(null);         // leaves cue 1
      p.cueChange(2);            // enters cue 2
      p.cueChange(3);            // adjacent cue 3: no stop between
      p.pause();
      p.seekStart(); p.seekEnd(true, 2);   // seek while paused: stop only
      p.play();
      p.buffering(); p.play();
      p.seekStart(); p.seekEnd(false, null); // seek out of cues while playing
      p.ended();
      return { calls, at: [m.cueAt([{start_s: 1, end_s: 2}], 2), m.cueAt([{start_s: 1, end_s: 2}], 1.5)?.start_s,
               m.cueIndexOf('cue-12'), m.cueIndexOf('<b>')] };
    }""")
    assert result["calls"] == ["run 1 play", "stop cue-exit", "run 2 enter", "run 3 enter", "stop pause",
                               "stop seeking", "run 2 play", "stop buffering", "run 2 play", "stop seeking",
                               "stop end"]
    assert result["at"] == [None, 1, 12, None]


def test_a_tutor_adds_a_cue_where_the_preview_is_paused_and_reads_the_cues_in_words(
        page, live_server: LiveServer, lesson_id: int) -> None:
    from middleware.auth.services import create_user
    from middleware.db import session_factory
    from middleware.models import Lesson

    with session_factory(live_server.app)() as session:
        tutor = create_user(session, "cue-tutor", "tutor", STUDENT_PASSWORD)
        session.flush()
        session.get(Lesson, lesson_id).author_id = tutor.id
        session.commit()
    log_in(page, live_server, "cue-tutor")
    page.goto(f"{live_server.url}/lessons/{lesson_id}/edit")
    cues = page.locator('[data-slot="cue-list"] li')
    cues.nth(1).wait_for()
    assert "0:01.0–0:03.0 Drive at 0.1 m/s, turning 0 rad/s" in cues.nth(0).inner_text()
    assert "Go to goal: goal x 0.3 m, goal y 0 m, speed 0.1 m/s" in cues.nth(1).inner_text()
    preview = page.locator('[data-field="preview"]')
    page.wait_for_function("v => v.readyState >= 1", arg=preview.element_handle())
    preview.evaluate("v => { v.currentTime = 8.5; }")  # as dragging the video's slider does
    page.locator('[data-field="cue-start"]').filter(has_text="0:08.5").wait_for()
    page.get_by_label("Lasts (seconds)").fill("1")
    page.get_by_label("What the robot does").select_option("stop")
    page.get_by_role("button", name="Add the cue").click()
    cues.nth(2).wait_for()
    assert "0:08.5–0:09.5 Stop the robot" in cues.nth(2).inner_text()
    assert "00:00:08.500 --> 00:00:09.500\n{\"stop\":true}" in page.locator("[name=cues]").input_value()
    page.get_by_role("button", name="Play the video from cue 2").click()
    page.wait_for_function("v => v.currentTime >= 5 && v.currentTime < 6", arg=preview.element_handle())
    page.get_by_role("button", name="Remove cue 1").click()
    page.locator('[data-field="result"]').filter(has_text="2 cue(s), all valid.").wait_for()
    page.get_by_role("button", name="Save", exact=True).click()
    page.locator('[data-field="result"]').filter(has_text="Saved.").wait_for()
    page.reload()
    assert "0:08.5–0:09.5 Stop the robot" in page.locator('[data-slot="cue-list"] li').nth(1).inner_text()
    ARTIFACTS_DIR.mkdir(exist_ok=True)
    page.set_viewport_size({"width": 390, "height": 844})
    page.screenshot(path=str(ARTIFACTS_DIR / "lesson-editor-cues-390.png"), full_page=True)
