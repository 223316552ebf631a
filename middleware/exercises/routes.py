"""Exercises pages and API: the catalogue, an exercise's page (the student's Python runs in their browser), code
versions, runs placed and graded by the server, and the tutor's view of the class's work.

Routes parse and respond; services.py decides. The exercise page and its worker are the only responses with
cross-origin isolation (COOP/COEP, so the worker can share memory with the page and be interrupted) and the
worker's the only one whose CSP allows WebAssembly ('wasm-unsafe-eval', which Pyodide needs)."""

from __future__ import annotations

import json
import logging
import secrets
import time
from datetime import datetime
from pathlib import Path
from typing import Any

from flask import Blueprint, Response, current_app, jsonify, render_template, request
from flask.typing import ResponseReturnValue
from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import current_user, login_required

from middleware.access.commands import Commander, robot_commands
from middleware.api.contract import ANY, BOOLEAN, ID, OBJECT, TIME, about, array, described, obj, one_of
from middleware.assessment.recording import robot_run
from middleware.browser_modules import csp_hash_source, import_map_text
from middleware.db import get_session
from middleware.errors import ApiError, Refused
from middleware.exercises import catalogue, leaderboard, schemas, services
from middleware.models.exercises import Exercise
from middleware.robots.link import RobotUnavailable
from middleware.robots.registry import robot_registry
from middleware.teaching.targets import PRACTICE_TARGET, resolve_target
from middleware.web import now
from protos.telelab.v1 import robot_pb2

log = logging.getLogger(__name__)
blueprint = Blueprint("exercises", __name__)
FRESH_ROBOT_WAIT_S = 40.0  # a submission's robot restarting: how long the request waits for it to answer again
PAGE_FOLDER = "pages/exercises"
# A new exercise's starting code: the loop every exercise has, in no language (the tutor writes the rest).
NEW_TEMPLATE = "from telelab import robot\n\nwhile robot.tick():\n    robot.set_velocity(0.0, 0.0)\n"
ISOLATION_HEADERS = {"Cross-Origin-Opener-Policy": "same-origin", "Cross-Origin-Embedder-Policy": "require-corp"}


def _read_log(robot_name: str, since: datetime, until: datetime) -> list[list[float]] | None:
    return robot_run(robot_name, since, until)


def _map_source() -> str:
    """The CSP source of the page's import map (the same the app's own policy names)."""
    return csp_hash_source(import_map_text(current_app.static_url_path or "/static"))


def _editor_policy(nonce: str) -> str:
    """The Content-Security-Policy of a page with the code editor: CodeMirror writes its styles in a <style> element
    carrying the response's nonce."""
    return ("default-src 'self'; img-src 'self' blob: data:; connect-src 'self' ws: wss:; "
            f"style-src 'self' 'nonce-{nonce}'; script-src 'self' {_map_source()}; object-src 'none'")


def _isolated(response: Response) -> Response:
    response.headers.update(ISOLATION_HEADERS)
    return response


@blueprint.get("/exercises")
@login_required
def index() -> ResponseReturnValue:
    """The catalogue, with the user's best submitted grade of each."""
    session = get_session()
    services.ensure_catalogue(session)
    exercises = services.catalogue(session)
    best = {e.id: max((r.fraction for r in services.own_runs(session, current_user, e, 200)
                       if r.mode == "submission" and r.fraction is not None), default=None) for e in exercises}
    return render_template("exercises/index.html", exercises=exercises, best=best,
                           editor=services.may_edit_catalogue(current_user))


@blueprint.get("/exercises/new")
@login_required
def new_form() -> ResponseReturnValue:
    """A tutor's or admin's form for a new exercise of the catalogue (it saves through POST /api/exercises)."""
    _require_catalogue_editor()
    return _definition_form(None)


@blueprint.get("/exercises/<slug>/edit")
@login_required
def edit_form(slug: str) -> ResponseReturnValue:
    """A tutor's or admin's form for an exercise's definition (it saves through PUT /api/exercises/<slug>)."""
    _require_catalogue_editor()
    return _definition_form(services.exercise_by_slug(get_session(), slug))


def _require_catalogue_editor() -> None:
    """The API's own rule (services.may_edit_catalogue): anyone else is refused the form as the API refuses them."""
    if not services.may_edit_catalogue(current_user):
        raise ApiError(403, "forbidden", gettext("Only tutors and admins change the exercise catalogue."))


def _definition_form(exercise: Exercise | None) -> ResponseReturnValue:
    """The catalogue's form, filled with the exercise's whole definition (its hidden start region too: only an editor
    reads this page), or a new exercise's starting values."""
    session = get_session()
    services.ensure_catalogue(session)
    if exercise is None:
        values: dict[str, Any] = {"slug": "", "title": "", "statement": "", "template": NEW_TEMPLATE, "scene": "lab",
                                  "start": [0.0, 0.0, 0.0], "random_starts": None, "time_limit_s": 60.0,
                                  "rubric": {"kind": "reach_goal"}}
    else:
        values = {"slug": exercise.slug, "title": exercise.title, "statement": exercise.statement,
                  "template": exercise.template, "scene": exercise.scene, "start": json.loads(exercise.start_json),
                  "random_starts": json.loads(exercise.random_starts_json), "time_limit_s": exercise.time_limit_s,
                  "rubric": json.loads(exercise.rubric_json)}
    scenes = sorted({"lab", *(e.scene for e in services.catalogue(session))})
    nonce = secrets.token_urlsafe(16)  # the template's editor (CodeMirror) writes its styles in a nonced <style>
    response = Response(render_template("exercises/form.html", exercise=exercise, values=values, scenes=scenes,
                                        kinds=schemas.RUBRIC_KIND_NAMES, parameters=schemas.RUBRIC_PARAMETERS,
                                        style_nonce=nonce))
    response.headers["Content-Security-Policy"] = _editor_policy(nonce)
    return response


@blueprint.get("/exercises/<slug>")
@login_required
def page(slug: str) -> ResponseReturnValue:
    """An exercise's page: the statement, the editor, Run and Submit, the console, the grade and the trace."""
    session = get_session()
    services.ensure_catalogue(session)
    exercise = services.exercise_by_slug(session, slug)
    nonce = secrets.token_urlsafe(16)  # CodeMirror writes its styles in a <style> element carrying this nonce
    response = Response(render_template("exercises/exercise.html", exercise=exercise, style_nonce=nonce,
                                        tutor=services.may_edit_catalogue(current_user),
                                        courses=services.attachable_courses(session, current_user, exercise),
                                        tests=services.tests_for(session, current_user, exercise),
                                        lab_robots=robot_registry().names()))
    response.headers["Content-Security-Policy"] = _editor_policy(nonce)
    return _isolated(response)


@blueprint.get("/exercises/python-worker.js")
@login_required
def worker() -> ResponseReturnValue:
    """The worker that runs the student's Python on Pyodide: its own CSP allows WebAssembly."""
    script = Path(current_app.static_folder or "", PAGE_FOLDER, "python-worker.js").read_bytes()
    response = Response(script, mimetype="text/javascript")
    response.headers["Cache-Control"] = "no-cache"
    response.headers["Content-Security-Policy"] = (
        "default-src 'self'; connect-src 'self'; "
        f"script-src 'self' 'wasm-unsafe-eval' {_map_source()}; object-src 'none'")
    return _isolated(response)


@blueprint.get("/exercises/<slug>/class")
@login_required
def class_page(slug: str) -> ResponseReturnValue:
    """A tutor's view of their students' code versions, runs and grades."""
    session = get_session()
    exercise = services.exercise_by_slug(session, slug)
    rows = services.class_overview(session, current_user, exercise)
    tests = [course for course in services.attachable_courses(session, current_user, exercise) if course["test"]]
    return render_template("exercises/class.html", exercise=exercise, rows=rows, tests=tests)


@blueprint.get("/api/exercises")
@login_required
@described(answers={200: obj(("exercises",), exercises=array(OBJECT))})
def list_exercises() -> ResponseReturnValue:
    """The catalogue."""
    session = get_session()
    services.ensure_catalogue(session)
    return jsonify({"exercises": [services.exercise_dict(e) for e in services.catalogue(session)]})


@blueprint.post("/api/exercises")
@login_required
@described(
    body=obj(
        ("slug", "title"),
        slug=about("1 to 63 lower-case letters, digits and -"),
        title=about("the exercise's title"),
        statement=about("what the student is asked"),
        template=about("the starting code"),
        scene=about("a scene"),
        start=about("the robot's start"),
        random_starts=about("true or false"),
        time_limit_s=about("seconds"),
        rubric=about("how it is graded"),
    ),
    answers={201: obj(("exercise",), exercise=OBJECT)},
    refusals=(409,),
)
def add() -> ResponseReturnValue:
    """A tutor or admin adds an exercise."""
    fields = schemas.definition(request.get_json(silent=True))
    exercise = services.add_exercise(get_session(), current_user, fields)
    return jsonify({"exercise": services.exercise_dict(exercise, full=True)}), 201


@blueprint.get("/api/exercises/<slug>")
@login_required
@described(answers={200: obj(("exercise",), exercise=OBJECT)})
def detail(slug: str) -> ResponseReturnValue:
    """An exercise, the user's latest code and their latest runs."""
    session = get_session()
    exercise = services.exercise_by_slug(session, slug)
    latest = services.latest_code(session, current_user.id, exercise.id)
    runs = services.own_runs(session, current_user, exercise)
    for run in runs:
        services.finish_if_overdue(session, run, _read_log, now())
    shown = services.exercise_dict(exercise, full=True)
    shown["template"] = catalogue.in_language(exercise.template)  # here only: a tutor's edit form saves it as written
    return jsonify({"exercise": shown,
                    "code": latest.code if latest else shown["template"],
                    "runs": [services.run_dict(r) for r in runs],
                    "tests": services.tests_for(session, current_user, exercise)})


@blueprint.put("/api/exercises/<slug>")
@login_required
@described(
    body=obj(
        ("title",),
        title=about("the exercise's title"),
        statement=about("what the student is asked"),
        template=about("the starting code"),
        scene=about("a scene"),
        start=about("the robot's start"),
        random_starts=about("true or false"),
        time_limit_s=about("seconds"),
        rubric=about("how it is graded"),
    ),
    answers={200: obj(("exercise",), exercise=OBJECT)},
    refusals=(409,),
)
def change(slug: str) -> ResponseReturnValue:
    """A tutor or admin rewrites an exercise."""
    session = get_session()
    exercise = services.exercise_by_slug(session, slug)
    fields = schemas.definition(request.get_json(silent=True), slug_required=False)
    services.change_exercise(session, current_user, exercise, fields, now())
    return jsonify({"exercise": services.exercise_dict(exercise, full=True)})


@blueprint.post("/api/exercises/<slug>/codes")
@login_required
@described(
    body=obj(("code",), code=about("the Python code")), answers={201: obj(("code_id",), code_id=ID)}, refusals=(413,)
)
def save(slug: str) -> ResponseReturnValue:
    """Saves a version of the user's code without running it."""
    session = get_session()
    exercise = services.exercise_by_slug(session, slug)
    body = schemas.body_object(request.get_json(silent=True))
    version = services.save_code(session, current_user, exercise, schemas.code(body.get("code")), now())
    return jsonify({"code_id": version.id}), 201


@blueprint.post("/api/exercises/<slug>/runs")
@login_required
@described(
    body=obj(
        ("code",),
        code=about("the Python code"),
        mode=one_of("practice", "submission"),
        robot=about('"practice" or a lab robot the user controls'),
    ),
    answers={201: obj(("run", "exercise"), run=OBJECT, exercise=OBJECT)},
    refusals=(409, 413, 503),
)
def start_run(slug: str) -> ResponseReturnValue:
    """Saves the code, places the user's robot at the run's start (hidden for a submission) and opens the run."""
    session = get_session()
    exercise = services.exercise_by_slug(session, slug)
    body = request.get_json(silent=True)
    text, mode = schemas.run_request(body)
    target = body.get("robot", PRACTICE_TARGET) if isinstance(body, dict) else PRACTICE_TARGET
    commander = resolve_target(target, current_user.id)
    scene = commander.link.info().scene_name  # an offline robot is already a 503 robot_offline
    version = services.save_code(session, current_user, exercise, text, now())

    def place(start: list[float]) -> None:
        if mode == "submission":
            _fresh_robot(commander)
        commander.place_robot(robot_pb2.Pose2D(x_m=start[0], y_m=start[1], theta_rad=start[2]),
                              kidnap=services.kidnaps(exercise))

    run = services.begin_run(session, current_user, exercise, version, mode, commander.robot_name, scene, place,
                             now, _read_log)
    return jsonify({"run": services.run_dict(run), "exercise": services.exercise_dict(exercise)}), 201


@blueprint.get("/api/exercise-runs/<int:run_id>")
@login_required
@described(answers={200: obj(("run",), run=OBJECT)})
def read_run(run_id: int) -> ResponseReturnValue:
    """A run (graded once its time is up, if its page never finished it), with its trace once graded."""
    session = get_session()
    run = services.run_for(session, current_user, run_id)
    services.finish_if_overdue(session, run, _read_log, now())
    return jsonify({"run": services.run_dict(run, with_trace=True)})


@blueprint.post("/api/exercise-runs/<int:run_id>/finish")
@login_required
@described(
    body=obj(report=obj(description="the pose the code reported (localization): {x_m, y_m, t_s}")),
    body_required=False,
    answers={200: obj(("run",), run=OBJECT, scene_boxes=ANY)},
    refusals=(409, 503),
)
def finish(run_id: int) -> ResponseReturnValue:
    """Ends the run now and grades it from the robot's own record; the body may only carry the pose the code
    reported (the localization exercise)."""
    session = get_session()
    report = schemas.finish_request(request.get_json(silent=True))
    run = services.run_for(session, current_user, run_id)
    services.finish_run(session, current_user, run, report, _read_log, now())
    scene = _scene_boxes(run.robot_name)
    return jsonify({"run": services.run_dict(run, with_trace=True), "scene_boxes": scene})


@blueprint.get("/api/exercises/<slug>/class")
@login_required
@described(answers={200: obj(("students",), students=ANY)})
def class_work(slug: str) -> ResponseReturnValue:
    """A tutor's students' code versions, runs and grades (JSON)."""
    session = get_session()
    exercise = services.exercise_by_slug(session, slug)
    return jsonify({"students": services.class_overview(session, current_user, exercise)})


def _fresh_robot(commander: Commander) -> None:
    """A submission runs on a fresh robot, not one drifted and mapped by practice: the robot's process is restarted
    (a new world: odometry, battery, map and goals as a robot started for the grade has them) and the request
    waits until it answers again. A robot that cannot restart itself (one run inside another program) is graded as
    it is; one that does not come back is a 503."""
    try:
        before = commander.link.health().restarts
        commander.restart()
    except Refused as refusal:
        log.info("a submission on %s runs on the robot as it is: %s", commander.robot_name, refusal)
        return
    deadline = time.monotonic() + FRESH_ROBOT_WAIT_S
    while time.monotonic() < deadline:
        try:
            if commander.link.health().restarts > before:
                return
        except RobotUnavailable:
            pass
        time.sleep(0.2)
    raise ApiError(503, "robot_offline", gettext("The robot started for your submission did not answer in time; "
                                                 "submit again."), "robot")


def _scene_boxes(robot_name: str) -> list[dict[str, float]]:
    """The walls and obstacles of the run's robot, for drawing the trace on the map (none if it is away)."""
    link = robot_commands().reachable(robot_name, current_user.id)
    if link is None:
        return []
    try:
        info = link.info()
    except RobotUnavailable:
        return []
    return [{"x": b.center_x_m, "y": b.center_y_m, "hx": b.half_x_m, "hy": b.half_y_m, "yaw": b.yaw_rad}
            for b in info.scene_boxes]


@blueprint.post("/api/courses/<int:course_id>/exercises")
@login_required
@described(
    body=obj(slug=about("the exercise"), deadline_at=about("ISO 8601"), points=about("its weight in the course")),
    answers={201: obj(("test",), test=OBJECT)},
    refusals=(409,),
)
def attach(course_id: int) -> ResponseReturnValue:
    """A course's tutor attaches an exercise as a test: {"slug", "deadline_at", "points"}."""
    session = get_session()
    slug, deadline, points = schemas.assignment(request.get_json(silent=True))
    exercise = services.exercise_by_slug(session, slug)
    test = services.attach_to_course(session, current_user, course_id, exercise, deadline, points)
    return jsonify({"test": {"course_id": test.course_id, "slug": exercise.slug,
                             "deadline_at": deadline.isoformat(), "points": test.points}}), 201


@blueprint.get("/courses/<int:course_id>/exercises/<slug>/leaderboard")
@login_required
def leaderboard_page(course_id: int, slug: str) -> ResponseReturnValue:
    """The course's leaderboard of the exercise, for its members (exercise-leaderboard.js reads it from the API,
    which says so when it is closed to students)."""
    session = get_session()
    exercise = services.exercise_by_slug(session, slug)
    course, test = leaderboard.course_test(session, course_id, exercise)
    leaderboard.require_member(session, current_user, test)
    return render_template("exercises/leaderboard.html", exercise=exercise, course=course)


@blueprint.get("/api/courses/<int:course_id>/exercises/<slug>/leaderboard")
@login_required
@described(answers={200: obj(
    ("course", "slug", "open", "may_open", "standings", "unranked"),
    course=OBJECT, slug=about("the exercise"), deadline_at=TIME, points=about("the test's points"), open=BOOLEAN,
    may_open=BOOLEAN, standings=array(obj(("rank", "username", "mark", "fraction", "reached_at", "you"))),
    unranked=about("how many of the course's students have no mark yet, not named"),
)})
def read_leaderboard(course_id: int, slug: str) -> ResponseReturnValue:
    """The course's students ranked by their mark on the exercise's test (best graded submission begun before the
    deadline; equal marks by who reached theirs first): the course's tutors always, its students while it is open."""
    session = get_session()
    exercise = services.exercise_by_slug(session, slug)
    return jsonify(leaderboard.leaderboard(session, current_user, course_id, exercise))


@blueprint.put("/api/courses/<int:course_id>/exercises/<slug>/leaderboard")
@login_required
@described(body=obj(("open",), open=BOOLEAN), answers={200: obj(("open",), open=BOOLEAN)})
def open_leaderboard(course_id: int, slug: str) -> ResponseReturnValue:
    """A course's tutor opens the exercise's leaderboard to the course's students ({"open": true}) or closes it."""
    session = get_session()
    exercise = services.exercise_by_slug(session, slug)
    body = schemas.body_object(request.get_json(silent=True))  # its "open" is a boolean: the contract checked it
    test = leaderboard.set_open(session, current_user, course_id, exercise, body["open"] is True)
    return jsonify({"open": test.leaderboard_open})
