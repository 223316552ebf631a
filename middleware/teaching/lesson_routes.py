"""Lesson pages and API: list, play, edit (tutors), the cue track, the video, and running cues."""

from __future__ import annotations

import time

from flask import (
    Blueprint,
    Response,
    current_app,
    flash,
    jsonify,
    redirect,
    render_template,
    request,
    send_from_directory,
    url_for,
)
from flask.typing import ResponseReturnValue
from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import current_user, login_required
from werkzeug.exceptions import RequestEntityTooLarge

from middleware.api.contract import (
    ANY,
    BOOLEAN,
    ID,
    OBJECT,
    STRING,
    about,
    array,
    described,
    nullable,
    number,
    obj,
    one_of,
    whole,
)
from middleware.db import get_session
from middleware.errors import ApiError, flashed, unless_refused
from middleware.extensions import csrf
from middleware.models import User
from middleware.models.teaching import Lesson
from middleware.robots.registry import robot_registry
from middleware.teaching.authority import require_author_rights
from middleware.teaching.command_form import RobotCommand
from middleware.teaching.cues import parse_cue_track
from middleware.teaching.lesson_tests import (
    check_lesson_tests,
    lesson_gate,
    lesson_results,
    require_before_test,
    teachable_exams,
)
from middleware.teaching.lesson_uploads import (
    DEFAULT_MAX_VIDEO_BYTES,
    MULTIPART_OVERHEAD,
    UploadRefused,
    store_video,
    too_large_message,
)
from middleware.teaching.lessons import (
    available_videos,
    check_lesson,
    delete_unused_video,
    lesson_dict,
    place_for_lesson,
    save_lesson,
    stored_cues,
    unused_videos,
    video_dir,
)
from middleware.teaching.progress import note_finished
from middleware.teaching.targets import (
    COMMAND_ANSWER,
    PRACTICE_TARGET,
    authoring_catalog,
    execute,
    reference_skills,
    resolve_target,
)

blueprint = Blueprint("lessons", __name__)
CUE = obj(("id", "index", "start_s", "end_s", "command", "line"), id=STRING, index=whole(1), start_s=number(),
          end_s=number(), command=OBJECT, line=whole())
# A lesson with its cues (lessons.lesson_dict).
LESSON = obj(("id", "slug", "title", "summary", "video_name", "topics", "before_exam_id", "after_exam_id", "cues",
              "cues_vtt"),
             id=ID, slug=STRING, title=STRING, summary=STRING, video_name=STRING, topics=array(STRING),
             before_exam_id=nullable(ID), after_exam_id=nullable(ID), cues=array(CUE), cues_vtt=STRING)
# A cue sent, or the stop: the command's answer, the cue's index, when it was heard (a sound cue: its tone).
CUE_RUN = {**COMMAND_ANSWER, "required": [*COMMAND_ANSWER["required"], "cue", "received_unix_ms"],
           "properties": {**COMMAND_ANSWER["properties"], "cue": whole(1), "received_unix_ms": number(),
                          "sound": OBJECT}}
STOPPED = {**COMMAND_ANSWER, "required": [*COMMAND_ANSWER["required"], "received_unix_ms"],
           "properties": {**COMMAND_ANSWER["properties"], "received_unix_ms": number()}}
PAPER_FIGURES = {"cue_to_robot_ms": [652.88, 543.94], "pause_detection_ms": 15.4}


def _user_id() -> int:
    return int(current_user.get_id())


def _require_tutor() -> None:
    if current_user.role not in ("tutor", "admin"):
        raise ApiError(403, "not_tutor", gettext("Only tutors write lessons."))


def _editable_lesson(lesson_id: int | None) -> Lesson | None:
    """The lesson to overwrite (None for a new one), when the user may change it."""
    if lesson_id is None:
        return None
    lesson = _lesson(lesson_id)
    session = get_session()
    require_author_rights(session, session.get(User, _user_id()), lesson.author_id, "lesson")  # type: ignore[arg-type]
    return lesson


def _lesson(lesson_id: int) -> Lesson:
    lesson = get_session().get(Lesson, lesson_id)
    if lesson is None:
        raise ApiError(404, "unknown_lesson", gettext("There is no such lesson."), "lesson_id")
    return lesson


@blueprint.get("/lessons")
@login_required
def index() -> ResponseReturnValue:
    """Every lesson."""
    lessons = get_session().query(Lesson).order_by(Lesson.title).all()
    return render_template("teaching/lessons.html", lessons=lessons)


@blueprint.get("/lessons/<int:lesson_id>")
@login_required
def play(lesson_id: int) -> ResponseReturnValue:
    """The lesson player."""
    lesson = _lesson(lesson_id)
    return render_template("teaching/lesson.html", lesson=lesson, paper=PAPER_FIGURES,
                           lab_robots=robot_registry().names(), gate=lesson_gate(get_session(), lesson, _user()))


def _user() -> User:
    return get_session().get(User, _user_id())  # type: ignore[return-value]


@blueprint.get("/lessons/<int:lesson_id>/results")
@login_required
def results_page(lesson_id: int) -> ResponseReturnValue:
    """The lesson's test before and after, compared per part (the student's own; the class's for its tutors)."""
    lesson = _lesson(lesson_id)
    return render_template("teaching/lesson_results.html", lesson=lesson,
                           results=lesson_results(get_session(), lesson, _user()))


@blueprint.get("/api/lessons/<int:lesson_id>/results")
@login_required
@described(answers={200: obj(("whose", "parts"), whose=ANY, students=ANY, parts=array(OBJECT))})
def results_api(lesson_id: int) -> ResponseReturnValue:
    """The comparison per part as JSON: {whose, students, parts: [{part, before, after, change, rating_*}]}."""
    found = lesson_results(get_session(), _lesson(lesson_id), _user())
    return jsonify({"whose": found.whose, "students": found.students, "parts": [p.to_dict() for p in found.parts]})


@blueprint.get("/lessons/new")
@blueprint.get("/lessons/<int:lesson_id>/edit")
@login_required
def edit(lesson_id: int | None = None) -> ResponseReturnValue:
    """The lesson editor (tutors)."""
    _require_tutor()
    lesson = _editable_lesson(lesson_id)
    return render_template("teaching/lesson_edit.html", lesson=lesson,
                           videos=available_videos(current_app.instance_path),
                           unused_videos=unused_videos(get_session(), current_app.instance_path),
                           uploaded_video=request.args.get("video"), skills=authoring_catalog(_user_id()),
                           exams=teachable_exams(get_session(), _user()),
                           max_video_mb=_max_video_bytes() // (1024 * 1024))


def _max_video_bytes() -> int:
    return int(current_app.config.get("LESSON_VIDEO_MAX_BYTES", DEFAULT_MAX_VIDEO_BYTES))


def _receive_video() -> str:
    """Checks the request (tutor, size, CSRF) and stores its "video" file; its new name or UploadRefused."""
    limit = _max_video_bytes()
    if request.content_length is not None and request.content_length > limit + MULTIPART_OVERHEAD:
        raise UploadRefused(413, "video_too_large", too_large_message(limit))  # refused before reading it
    # The app reads at most MAX_CONTENT_LENGTH (2 MB) of any request; this route alone takes a video,
    # so the limit is raised here, for this request, only after the login and the tutor role were checked.
    request.max_content_length = limit + MULTIPART_OVERHEAD
    try:
        csrf.protect()  # exempt from the automatic check, which would read the body under the 2 MB limit
        upload = request.files.get("video")
    except RequestEntityTooLarge:
        raise UploadRefused(413, "video_too_large", too_large_message(limit)) from None
    if upload is None or not upload.filename:
        raise UploadRefused(400, "missing_video", gettext("video: choose a .webm or .mp4 file to upload."))
    try:
        return store_video(current_app.instance_path, upload.filename, upload.stream, limit)
    finally:
        upload.close()


@blueprint.post("/lessons/videos")
@blueprint.post("/api/lessons/videos", endpoint="upload_video_api")
@csrf.exempt
@login_required
@described(
    form=obj(("video",), video={"type": "string", "format": "binary", "description": "the lesson video"}),
    query={"lesson": whole(1, 2**31 - 1)},
    answers={201: obj(("video_name", "videos"), video_name=STRING, videos=array())},
    refusals=(413,),
    form_read_by_view=True,
)
def upload_video() -> ResponseReturnValue:
    """Uploads a lesson video (tutors; multipart field "video", with the CSRF token).

    The API answers {"video_name"} or an error naming the field; the editor's form is sent back to the
    editor, with the new video chosen, or with the error.
    """
    api = request.path.startswith("/api/")
    _require_tutor()
    lesson_id = request.args.get("lesson", type=int)
    back = url_for("lessons.edit", lesson_id=lesson_id) if lesson_id else url_for("lessons.edit")

    def upload() -> ResponseReturnValue:
        name = _receive_video()
        if api:
            return jsonify({"video_name": name, "videos": available_videos(current_app.instance_path)}), 201
        flash(gettext("Uploaded as %(name)s; it is chosen below as the lesson's video.", name=name), "success")
        return redirect(f"{back}?video={name}", 303)

    return upload() if api else unless_refused(upload, flashed(back), about_the_page=())



@blueprint.post("/lessons/videos/<name>/delete")
@blueprint.delete("/api/lessons/videos/<name>", endpoint="delete_video_api")
@login_required
@described(
    query={"lesson": whole(1, 2**31 - 1)},
    answers={200: obj(("deleted", "videos"), deleted=STRING, videos=array())},
    refusals=(409,),
)
def delete_video(name: str) -> ResponseReturnValue:
    """Deletes an uploaded video no lesson plays (tutors). The editor's button comes back to the editor."""
    api = request.path.startswith("/api/")
    _require_tutor()
    lesson_id = request.args.get("lesson", type=int)
    back = url_for("lessons.edit", lesson_id=lesson_id) if lesson_id else url_for("lessons.edit")

    def delete() -> ResponseReturnValue:
        delete_unused_video(get_session(), current_app.instance_path, name)
        if api:
            return jsonify({"deleted": name, "videos": available_videos(current_app.instance_path)})
        flash(gettext("Deleted %(name)s.", name=name), "success")
        return redirect(back, 303)

    return delete() if api else unless_refused(delete, flashed(back), about_the_page=())


@blueprint.get("/lessons/<int:lesson_id>/cues.vtt")
@login_required
def cue_track(lesson_id: int) -> ResponseReturnValue:
    """The canonical WebVTT cue track (commands only, written by the server)."""
    return Response(_lesson(lesson_id).cues_vtt, mimetype="text/vtt")


@blueprint.get("/lessons/videos/<name>")
@login_required
def preview_video(name: str) -> ResponseReturnValue:
    """A video of the lessons folder by name, for the editor's preview (tutors)."""
    _require_tutor()
    if name not in available_videos(current_app.instance_path):
        raise ApiError(404, "unknown_video", gettext("There is no video by that name in the lessons folder."), "name")
    return send_from_directory(video_dir(current_app.instance_path), name, conditional=True)


@blueprint.get("/lessons/<int:lesson_id>/video")
@login_required
def video(lesson_id: int) -> ResponseReturnValue:
    """The lesson's video file (range requests supported, so seeking works)."""
    lesson = _lesson(lesson_id)
    return send_from_directory(video_dir(current_app.instance_path), lesson.video_name, conditional=True)


@blueprint.get("/api/lessons/<int:lesson_id>")
@login_required
@described(answers={200: LESSON})
def lesson_api(lesson_id: int) -> ResponseReturnValue:
    """A lesson with its cues."""
    return jsonify(lesson_dict(_lesson(lesson_id)))


@blueprint.post("/api/lessons/check")
@login_required
@described(
    body=obj(cues=about("the cue track (WebVTT or SRT); missing or wrong, it is answered with its errors")),
    answers={200: obj(("cues", "errors"), cues=array(OBJECT), errors=array(OBJECT))},
    refusals=(503,),
)
def check() -> ResponseReturnValue:
    """Checks a cue track without saving: {"cues": text} -> the cues and every error by line."""
    _require_tutor()
    body = request.get_json(silent=True)
    if not isinstance(body, dict):
        raise ApiError(400, "invalid_field", gettext("Send a JSON object: {\"cues\": \"WEBVTT ...\"}."), "body")
    cues, errors = parse_cue_track(body.get("cues"), reference_skills(_user_id()))
    return jsonify({"cues": [c.to_dict() for c in cues], "errors": [e.to_dict() for e in errors]})


@blueprint.post("/api/lessons")
@blueprint.put("/api/lessons/<int:lesson_id>")
@login_required
@described(
    body=obj(
        title=about("the lesson's title"),
        summary=about("what it teaches"),
        slug=about("its address"),
        topics=about("its topics"),
        video_name=about("its video's name"),
        cues=about("the cue track (WebVTT or SRT); a wrong one is answered with every error by line"),
    ),
    answers={200: LESSON, 201: LESSON},
    refusals=(409, 503),
)
def save(lesson_id: int | None = None) -> ResponseReturnValue:
    """Creates or updates a lesson after checking every cue against the robot's skills."""
    _require_tutor()
    lesson = _editable_lesson(lesson_id)
    draft = check_lesson(request.get_json(silent=True), reference_skills(_user_id()),
                         available_videos(current_app.instance_path))
    check_lesson_tests(get_session(), _user(), draft.before_exam_id, draft.after_exam_id)
    lesson = save_lesson(get_session(), draft, _user_id(), lesson)
    return jsonify(lesson_dict(lesson)), 200 if lesson_id is not None else 201


def _run_body() -> tuple[dict[str, object], float]:
    body = request.get_json(silent=True)
    if not isinstance(body, dict):
        raise ApiError(400, "invalid_field", gettext("Send a JSON object: {\"target\": \"practice\"}."), "body")
    hold_s = body.get("hold_s", 10.0)
    if isinstance(hold_s, bool) or not isinstance(hold_s, int | float) or not 0.1 <= hold_s <= 10:
        raise ApiError(400, "invalid_field", gettext("hold_s must be a number of seconds from 0.1 to 10."), "hold_s")
    return body, float(hold_s)


@blueprint.post("/api/lessons/<int:lesson_id>/cues/<int:index>/run")
@login_required
@described(
    body=obj(target=about('"practice" or a robot the user controls')),
    body_required=False,
    answers={202: CUE_RUN},
    refusals=(409, 503),
)
def run_cue(lesson_id: int, index: int) -> ResponseReturnValue:
    """Sends the stored command of cue `index` (never a command from the page) to the learner's target."""
    received_at = time.perf_counter()
    received_unix_ms = time.time() * 1000
    body, hold_s = _run_body()
    lesson = _lesson(lesson_id)
    require_before_test(get_session(), lesson, _user())
    cues = stored_cues(lesson)
    if not 1 <= index <= len(cues):
        raise ApiError(404, "unknown_cue", gettext("The lesson has no such cue."), "index")
    command = cues[index - 1].command
    # A sound cue: the robot stands still (the 2022 paper's third part) while the page plays the tone and its caption.
    sound = command.to_dict()["sound"] if command.kind == "sound" else None
    result = execute(resolve_target(body.get("target"), _user_id()), command.motion(), received_at, hold_s)
    return jsonify({**result, "cue": index, "received_unix_ms": round(received_unix_ms, 3),
                    **({"sound": sound} if sound else {})}), 202


@blueprint.post("/api/lessons/<int:lesson_id>/start")
@login_required
@described(
    body=obj(target=about('"practice" or a robot the user controls')),
    body_required=False,
    answers={200: obj(("at", "message"), at=one_of("dock", "here"), message=STRING)},
    refusals=(409, 503),
)
def start_lesson(lesson_id: int) -> ResponseReturnValue:
    """Places the learner's target where the lesson's video starts (their practice robot: at its dock)."""
    require_before_test(get_session(), _lesson(lesson_id), _user())
    body, _hold_s = _run_body()
    return jsonify(place_for_lesson(resolve_target(body.get("target"), _user_id()),
                                    body.get("target") == PRACTICE_TARGET))


@blueprint.post("/api/lessons/<int:lesson_id>/watched")
@login_required
@described(answers={200: obj(("recorded",), recorded=BOOLEAN)})
def watched(lesson_id: int) -> ResponseReturnValue:
    """The player saw the lesson's video to its end: recorded for the tutors' analytics (and the xAPI statement
    "watched"); a repeat within a minute is not recorded again."""
    lesson = _lesson(lesson_id)
    return jsonify({"recorded": note_finished(get_session(), _user_id(), "lesson_watched", lesson.id)})


@blueprint.post("/api/lessons/stop")
@login_required
@described(
    body=obj(target=about('"practice" or a robot the user controls')),
    body_required=False,
    answers={200: STOPPED},
    refusals=(409, 503),
)
def stop() -> ResponseReturnValue:
    """Stops the learner's target at once (pause, seek, buffering, end)."""
    received_at = time.perf_counter()
    received_unix_ms = time.time() * 1000
    body, _hold_s = _run_body()
    result = execute(resolve_target(body.get("target"), _user_id()), RobotCommand("stop"), received_at)
    return jsonify({**result, "received_unix_ms": round(received_unix_ms, 3)})
