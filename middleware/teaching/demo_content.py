"""The demo data of the teaching area: four example tours and one video lesson recorded from the simulator, and the
first tour and the lesson in Spanish (the Spanish lesson's tests are the Spanish demo course's)."""

from __future__ import annotations

import logging
from pathlib import Path

from flask import Flask
from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.db import session_factory
from middleware.demo_course import (
    LESSON_AFTER_TITLE,
    LESSON_AFTER_TITLE_ES,
    LESSON_BEFORE_TITLE,
    LESSON_BEFORE_TITLE_ES,
)
from middleware.models import User
from middleware.models.assessment import Exam
from middleware.models.teaching import Lesson, Tour
from middleware.teaching.cues import parse_cue_track
from middleware.teaching.demo_video import record_demo_video
from middleware.teaching.lessons import LessonDraft, save_lesson, video_dir
from middleware.teaching.tours import save_tour

log = logging.getLogger(__name__)
DEMO_VIDEO = "demo-first-moves.webm"
DEMO_VIDEO_LENGTH_S = 24.0
DEMO_CUES = """WEBVTT

00:00:01.000 --> 00:00:05.000
{"drive": {"linear_mps": 0.2, "angular_radps": 0}}

00:00:06.000 --> 00:00:09.000
{"drive": {"linear_mps": 0, "angular_radps": 0.8}}

00:00:10.000 --> 00:00:20.000
{"skill": "go_to_goal", "parameters": {"goal_x_m": 0.5, "goal_y_m": 0.5, "speed_mps": 0.25}}

00:00:21.000 --> 00:00:22.500
{"sound": {"frequency_hz": 880, "duration_s": 0.6, "caption": "The robot beeps: it has reached its goal"}}

00:00:22.500 --> 00:00:23.000
{"stop": true}
"""

DEMO_TOURS = [
    {"slug": "direct-control", "topics": "direct control, odometry",
     "title": "Direct control",
     "summary": "Drive the robot yourself: speeds and the deadman.",
     "steps": [
         {"title": "The camera", "text": "This is what the robot sees. Watch it while the robot moves.",
          "panel": "camera", "condition": {"type": "time", "seconds": 3}},
         {"title": "Forward", "text": "Direct control holds a speed for a while, then stops by itself.",
          "panel": "drive", "command": {"skill": "direct_control",
                                        "parameters": {"linear_mps": 0.2, "angular_radps": 0.0, "duration_s": 3.0}},
          "condition": {"type": "skill_finished"}},
         {"title": "Turn", "text": "Now a turn on the spot: the odometry shows the heading change.",
          "panel": "odometry", "command": {"skill": "direct_control",
                                           "parameters": {"linear_mps": 0.0, "angular_radps": 0.8, "duration_s": 2.0}},
          "condition": {"type": "skill_finished"}},
         {"title": "Your turn", "text": "Open the console and drive with the arrow keys.", "panel": "drive",
          "condition": {"type": "manual"}}]},
    {"slug": "go-to-goal", "topics": "navigation, path planning",
     "title": "Go to a goal", "summary": "The robot plans a path and drives to a point.",
     "steps": [
         {"title": "The map", "text": "The lab from above: the robot, its laser and the obstacles.", "panel": "map",
          "condition": {"type": "time", "seconds": 3}},
         {"title": "Go", "text": "Go-to-goal plans with A* and replans when the way is blocked.",
          "panel": "skill-go_to_goal",
          "command": {"skill": "go_to_goal", "parameters": {"goal_x_m": 0.6, "goal_y_m": 0.4, "speed_mps": 0.3}},
          "condition": {"type": "skill_finished"}},
         {"title": "Done", "text": "The goal counts as reached once the robot is within the skill's allowed error "
                                   "of it.", "panel": "odometry",
          "condition": {"type": "manual"}}]},
    {"slug": "wall-following", "topics": "sensors, sonar, wall following",
     "title": "Wall following", "summary": "Keep a distance to a wall with the sonars.",
     "steps": [
         {"title": "Sonars", "text": "The ring of sonars measures the distance to the walls.", "panel": "sonar",
          "condition": {"type": "time", "seconds": 3}},
         {"title": "Follow", "text": "The robot keeps 0.4 m from the wall on its right for ten seconds.",
          "panel": "skill-wall_following",
          "command": {"skill": "wall_following",
                      "parameters": {"distance_m": 0.4, "side": "right", "speed_mps": 0.2, "duration_s": 10.0}},
          "condition": {"type": "skill_finished"}}]},
    {"slug": "localization", "topics": "laser, localization, sensors",
     "title": "Localization", "summary": "Where am I? Particles converge on the pose.",
     "steps": [
         {"title": "Laser", "text": "The laser sees walls and furniture; localization compares them with the plan.",
          "panel": "laser", "condition": {"type": "time", "seconds": 3}},
         {"title": "Particles", "text": "Each particle is a guess; watch them gather as the robot turns.",
          "panel": "map", "command": {"skill": "localization", "parameters": {"particle_count": 400}},
          "condition": {"type": "time", "seconds": 4}},
         {"title": "Turn to see more", "text": "Turning shows the laser more of the room.", "panel": "map",
          "command": {"skill": "direct_control",
                      "parameters": {"linear_mps": 0.0, "angular_radps": 0.6, "duration_s": 5.0}},
          "condition": {"type": "skill_finished"}}]},
    # In Spanish, beside the English ones (docs/languages.md): the first tour, as a Spanish-speaking tutor writes it.
    {"slug": "control-directo", "topics": "control directo, odometría",
     "title": "Control directo",
     "summary": "Conduce tú el robot: velocidades y el hombre muerto.",
     "steps": [
         {"title": "La cámara", "text": "Esto es lo que ve el robot. Míralo mientras se mueve.",
          "panel": "camera", "condition": {"type": "time", "seconds": 3}},
         {"title": "Adelante", "text": "El control directo mantiene una velocidad un rato y luego para solo.",
          "panel": "drive", "command": {"skill": "direct_control",
                                        "parameters": {"linear_mps": 0.2, "angular_radps": 0.0, "duration_s": 3.0}},
          "condition": {"type": "skill_finished"}},
         {"title": "Giro", "text": "Ahora un giro sobre sí mismo: la odometría muestra el cambio de orientación.",
          "panel": "odometry", "command": {"skill": "direct_control",
                                           "parameters": {"linear_mps": 0.0, "angular_radps": 0.8, "duration_s": 2.0}},
          "condition": {"type": "skill_finished"}},
         {"title": "Te toca", "text": "Abre la consola y conduce con las flechas.", "panel": "drive",
          "condition": {"type": "manual"}}]},
]


def seed_demo_content(app: Flask, record_video: bool = True) -> list[str]:
    """Adds the example tours and the demo lesson when missing (the video is recorded if absent)."""
    added: list[str] = []
    cues, errors = parse_cue_track(DEMO_CUES, None)
    assert not errors, errors
    with app.app_context():  # the app's shared folder, where every host serves lesson videos from
        video = video_dir(app.instance_path) / DEMO_VIDEO
    if record_video and not video.exists():
        print(f"recording the demo lesson's video from the simulator ({DEMO_VIDEO_LENGTH_S:.0f} s)…", flush=True)
        if not record_demo_video(Path(video), cues, DEMO_VIDEO_LENGTH_S):
            log.warning("ffmpeg is missing: the demo lesson has no video (`make ffmpeg` installs it)")
    with session_factory(app)() as session:
        tutor = session.scalar(select(User).where(User.username == "tutor"))
        author = tutor.id if tutor else None
        for data in DEMO_TOURS:
            if session.scalar(select(Tour).where(Tour.slug == data["slug"])) is None:
                save_tour(session, data, None, author)
                added.append(f"tour {data['slug']}")
        if video.exists() and session.scalar(select(Lesson).where(Lesson.slug == "first-moves")) is None:
            draft = LessonDraft("first-moves", "First moves", "The video drives your robot: forward, a turn, "
                                "then a goal. Pause and the robot stops.", DEMO_VIDEO, cues,
                                "direct control, navigation, odometry", *_lesson_tests(session))
            save_lesson(session, draft, author)
            added.append("lesson first-moves")
        if video.exists() and session.scalar(select(Lesson).where(Lesson.slug == "primeros-movimientos")) is None:
            save_lesson(session, LessonDraft(  # the same video and cues, told in Spanish (docs/languages.md)
                "primeros-movimientos", "Primeros movimientos", "El vídeo conduce tu robot: adelante, un giro y "
                "luego un objetivo. Si pausas, el robot se para.", DEMO_VIDEO, cues,
                "control directo, navegación, odometría", *_lesson_tests(session, LESSON_BEFORE_TITLE_ES,
                                                                         LESSON_AFTER_TITLE_ES)), author)
            added.append("lesson primeros-movimientos")
        session.commit()
    return added


def _lesson_tests(session: Session, before: str = LESSON_BEFORE_TITLE,
                  after: str = LESSON_AFTER_TITLE) -> tuple[int | None, int | None]:
    """The demo course's tests before and after the demo lesson, found by title: the English course's, or the
    Spanish course's for the Spanish lesson (None where the course has none)."""
    return tuple(session.scalar(select(Exam.id).where(Exam.title == title).order_by(Exam.id))  # type: ignore[return-value]
                 for title in (before, after))
