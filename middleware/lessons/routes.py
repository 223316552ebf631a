"""Lesson pages and API: list, play, edit (tutors), the cue track, the video, and running cues."""

from __future__ import annotations

import time

from flask import Blueprint, Response, current_app, jsonify, render_template, request, send_from_directory
from flask_login import current_user, login_required

from middleware.db import get_session
from middleware.errors import ApiError
from middleware.lessons.commands import RobotCommand
from middleware.lessons.cues import parse_cue_track
from middleware.lessons.services import (
    LessonInvalid,
    available_videos,
    check_lesson,
    lesson_dict,
    save_lesson,
    stored_cues,
    video_dir,
)
from middleware.models.teaching import Lesson
from middleware.practice.control import execute, reference_skills, resolve_target

blueprint = Blueprint("lessons", __name__)
PAPER_FIGURES = {"cue_to_robot_ms": [652.88, 543.94], "pause_detection_ms": 15.4}


def _user_id() -> int:
    return int(current_user.get_id())


def _require_tutor() -> None:
    if current_user.role not in ("tutor", "admin"):
        raise ApiError(403, "not_tutor", "Only tutors write lessons.")


def _lesson(lesson_id: int) -> Lesson:
    lesson = get_session().get(Lesson, lesson_id)
    if lesson is None:
        raise ApiError(404, "unknown_lesson", "There is no such lesson.", "lesson_id")
    return lesson


def _invalid(error: LessonInvalid):  # type: ignore[no-untyped-def]
    first = error.errors[0]
    where = f" (line {first.line})" if first.line else ""
    body = {"error": {"code": "invalid_lesson", "message": first.message + where, "field": first.field},
            "errors": [e.to_dict() for e in error.errors]}
    return jsonify(body), 400


@blueprint.get("/lessons")
@login_required
def index():  # type: ignore[no-untyped-def]
    """Every lesson."""
    lessons = get_session().query(Lesson).order_by(Lesson.title).all()
    return render_template("teaching/lessons.html", lessons=lessons)


@blueprint.get("/lessons/<int:lesson_id>")
@login_required
def play(lesson_id: int):  # type: ignore[no-untyped-def]
    """The lesson player."""
    from middleware.robots.registry import robot_registry

    return render_template("teaching/lesson.html", lesson=_lesson(lesson_id), paper=PAPER_FIGURES,
                           lab_robots=robot_registry().names())


@blueprint.get("/lessons/new")
@blueprint.get("/lessons/<int:lesson_id>/edit")
@login_required
def edit(lesson_id: int | None = None):  # type: ignore[no-untyped-def]
    """The lesson editor (tutors)."""
    _require_tutor()
    lesson = _lesson(lesson_id) if lesson_id is not None else None
    return render_template("teaching/lesson_edit.html", lesson=lesson,
                           videos=available_videos(current_app.instance_path))


@blueprint.get("/lessons/<int:lesson_id>/cues.vtt")
@login_required
def cue_track(lesson_id: int):  # type: ignore[no-untyped-def]
    """The canonical WebVTT cue track (commands only, written by the server)."""
    return Response(_lesson(lesson_id).cues_vtt, mimetype="text/vtt")


@blueprint.get("/lessons/<int:lesson_id>/video")
@login_required
def video(lesson_id: int):  # type: ignore[no-untyped-def]
    """The lesson's video file (range requests supported, so seeking works)."""
    lesson = _lesson(lesson_id)
    return send_from_directory(video_dir(current_app.instance_path), lesson.video_name, conditional=True)


@blueprint.get("/api/lessons/<int:lesson_id>")
@login_required
def lesson_api(lesson_id: int):  # type: ignore[no-untyped-def]
    """A lesson with its cues."""
    return jsonify(lesson_dict(_lesson(lesson_id)))


@blueprint.post("/api/lessons/check")
@login_required
def check():  # type: ignore[no-untyped-def]
    """Checks a cue track without saving: {"cues": text} -> the cues and every error by line."""
    _require_tutor()
    body = request.get_json(silent=True)
    if not isinstance(body, dict):
        raise ApiError(400, "invalid_field", 'Send a JSON object: {"cues": "WEBVTT ..."}.', "body")
    cues, errors = parse_cue_track(body.get("cues"), reference_skills(_user_id()))
    return jsonify({"cues": [c.to_dict() for c in cues], "errors": [e.to_dict() for e in errors]})


@blueprint.post("/api/lessons")
@blueprint.put("/api/lessons/<int:lesson_id>")
@login_required
def save(lesson_id: int | None = None):  # type: ignore[no-untyped-def]
    """Creates or updates a lesson after checking every cue against the robot's skills."""
    _require_tutor()
    session = get_session()
    lesson = _lesson(lesson_id) if lesson_id is not None else None
    try:
        draft = check_lesson(request.get_json(silent=True), reference_skills(_user_id()),
                             available_videos(current_app.instance_path))
        lesson = save_lesson(session, draft, _user_id(), lesson)
    except LessonInvalid as error:
        session.rollback()
        return _invalid(error)
    session.commit()
    return jsonify(lesson_dict(lesson)), 200 if lesson_id is not None else 201


def _run_body() -> tuple[dict[str, object], float]:
    body = request.get_json(silent=True)
    if not isinstance(body, dict):
        raise ApiError(400, "invalid_field", 'Send a JSON object: {"target": "practice"}.', "body")
    hold_s = body.get("hold_s", 10.0)
    if isinstance(hold_s, bool) or not isinstance(hold_s, int | float) or not 0.1 <= hold_s <= 10:
        raise ApiError(400, "invalid_field", "hold_s must be a number of seconds from 0.1 to 10.", "hold_s")
    return body, float(hold_s)


@blueprint.post("/api/lessons/<int:lesson_id>/cues/<int:index>/run")
@login_required
def run_cue(lesson_id: int, index: int):  # type: ignore[no-untyped-def]
    """Sends the stored command of cue `index` (never a command from the page) to the learner's target."""
    received_at = time.perf_counter()
    received_unix_ms = time.time() * 1000
    body, hold_s = _run_body()
    cues = stored_cues(_lesson(lesson_id))
    if not 1 <= index <= len(cues):
        raise ApiError(404, "unknown_cue", "The lesson has no such cue.", "index")
    result = execute(resolve_target(body.get("target"), _user_id()), cues[index - 1].command, received_at, hold_s)
    return jsonify({**result, "cue": index, "received_unix_ms": round(received_unix_ms, 3)}), 202


@blueprint.post("/api/lessons/stop")
@login_required
def stop():  # type: ignore[no-untyped-def]
    """Stops the learner's target at once (pause, seek, buffering, end)."""
    received_at = time.perf_counter()
    received_unix_ms = time.time() * 1000
    body, _hold_s = _run_body()
    result = execute(resolve_target(body.get("target"), _user_id()), RobotCommand("stop"), received_at)
    return jsonify({**result, "received_unix_ms": round(received_unix_ms, 3)})
