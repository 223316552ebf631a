"""The experiment page and its JSON API: trials for students, delays and the class's results for tutors."""

from __future__ import annotations

import json
import logging
from collections.abc import Callable
from typing import TypeVar

from flask import Blueprint, Response, jsonify, render_template, request
from flask.typing import ResponseReturnValue
from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import current_user, login_required
from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.access.commands import robot_commands
from middleware.api.contract import BOOLEAN, ID, OBJECT, STRING, about, array, described, nullable, number, obj, whole
from middleware.courses.authority import taught_course_ids
from middleware.db import after_commit, get_session
from middleware.errors import ApiError
from middleware.experiment import protocol, services
from middleware.experiment.delay import delay_book
from middleware.experiment.progress import TrackRunNow, finished_in_trial, progress_view, track_route
from middleware.experiment.trial_rules import FEEDBACK_PREFERENCE_KEY
from middleware.models import Course, CourseMembership, User, UserPreference
from middleware.models.accounts import utc_now
from middleware.models.experiment import TRIAL_OPEN, Trial
from middleware.models.farm import PersonalRobotRecord
from middleware.robots.link import CommandRefused, RobotLink, RobotUnavailable
from middleware.robots.registry import robot_registry

blueprint = Blueprint("experiment", __name__)
log = logging.getLogger(__name__)
T = TypeVar("T")


def _actor() -> User:
    return get_session().get(User, int(current_user.get_id()))  # type: ignore[return-value]


def _run(action: Callable[[Session], T]) -> T:
    """Runs a service call in the request's unit of work; once it is committed, this process's viewers see a
    changed delay at once (trials and tutors change delays)."""
    result = action(get_session())
    after_commit(delay_book().forget)
    return result


TRIAL = obj(("id", "course_id", "robot_name", "course", "delay_s", "feedback", "commands_delayed", "status",
             "total_time_s", "errors"),
            id=ID, course_id=nullable(ID), robot_name=STRING, course=STRING, delay_s=number(), feedback=BOOLEAN,
            commands_delayed=BOOLEAN, status=STRING, total_time_s=nullable(number()), errors=whole())
# The student's page (state): the protocol's step, their trial and its run, what a new trial may use.
STATE = obj(("protocol", "trial", "run", "last_trial", "robots", "courses", "delay_s"),
            protocol=obj(("details_answered", "consent", "learning_s", "learning_left_s", "learning_started",
                          "learning_done", "commands_delayed"),
                         details_answered=BOOLEAN, consent=BOOLEAN, learning_s=number(),
                         learning_left_s=nullable(number()), learning_started=BOOLEAN, learning_done=BOOLEAN,
                         commands_delayed=BOOLEAN),
            trial=nullable(TRIAL), run=nullable(obj(("online", "finished", "message"), online=BOOLEAN,
                                                   finished=BOOLEAN, message=STRING)),
            last_trial=nullable(TRIAL),
            robots=array(obj(("name", "scene", "own"), name=STRING, scene=STRING, own=BOOLEAN)),
            courses=array(obj(("id", "code", "title"), id=ID, code=STRING, title=STRING)), delay_s=number())
PARTICIPANT = obj(("consent", "age", "location", "games_experience", "robots_experience"), consent=BOOLEAN,
                  age=nullable(whole()), location=nullable(STRING), games_experience=nullable(STRING),
                  robots_experience=nullable(STRING))
_COUNTS = {"type": "object", "additionalProperties": whole(0)}
# The tutor's results: every trial, the means per condition, their comparisons, the participants' table.
RESULTS = obj(("trials", "summary", "comparisons", "participants", "orders"),
              trials=array({**TRIAL, "required": [*TRIAL["required"], "username"],
                            "properties": {**TRIAL["properties"], "username": STRING}}),
              summary=array(obj(("course", "delay_s", "feedback", "n", "mean_time_s", "standard_error_s",
                                 "mean_errors"),
                                course=STRING, delay_s=number(), feedback=BOOLEAN, n=whole(0), mean_time_s=number(),
                                standard_error_s=nullable(number()), mean_errors=number())),
              comparisons=array(obj(("course", "delay_s", "preview_saves", "on_vs_control", "off_vs_control"),
                                    course=STRING, delay_s=number(), preview_saves=nullable(number()),
                                    on_vs_control=nullable(number()), off_vs_control=nullable(number()))),
              participants=obj(("participants", "consenting", "age_min", "age_max", "age_mean", "location",
                                "games_experience", "robots_experience", "orders_in_use"),
                               participants=whole(0), consenting=whole(0), age_min=nullable(whole()),
                               age_max=nullable(whole()), age_mean=nullable(number()), location=_COUNTS,
                               games_experience=_COUNTS, robots_experience=_COUNTS, orders_in_use=array(whole(0))),
              orders=whole(0))


def _trial_dict(trial: Trial) -> dict[str, object]:
    return {"id": trial.id, "course_id": trial.course_id, "robot_name": trial.robot_name, "course": trial.course,
            "delay_s": trial.delay_s, "feedback": trial.feedback, "commands_delayed": trial.commands_delayed,
            "status": trial.status, "total_time_s": trial.total_time_s, "errors": trial.errors}


def _json_object() -> dict[str, object]:
    body = request.get_json(silent=True)
    if not isinstance(body, dict):
        raise ApiError(400, "invalid_field", gettext("Send a JSON object."), "body")
    return body


def track_robots(user_id: int) -> list[dict[str, object]]:
    """The user's own robot when it runs a track scene (their robot in a class session), then the online lab
    robots whose skill server runs one."""
    registry = robot_registry()
    found: list[dict[str, object]] = []
    own = get_session().scalar(select(PersonalRobotRecord).where(PersonalRobotRecord.owner_id == user_id,
                                                                 PersonalRobotRecord.address != ""))
    if own is not None and own.scene in services.COURSES and registry.get(own.name) is not None:
        found.append({"name": own.name, "scene": own.scene, "own": True})
    for name in registry.names():
        link = registry.get(name)
        try:
            scene = link.info().scene_name if link is not None else ""
        except RobotUnavailable:
            continue
        if scene in services.COURSES:
            found.append({"name": name, "scene": scene, "own": False})
    return found


def _track_run_now(link: RobotLink | None) -> TrackRunNow | None:
    """The robot's track run now; None when the robot is gone or runs no track. RobotUnavailable passes up."""
    run = link.track_run() if link is not None else None
    if run is None or not run.is_track:
        return None
    return TrackRunNow(run.phase, run.attempt, run.elapsed_s, run.errors, run.last_attempt, run.last_total_time_s,
                        run.last_errors, run.last_finished_unix_s, run.started_unix_s, run.last_started_unix_s)


def _restart_run_after_commit(session: Session, trial: Trial) -> None:
    """Once the trial is begun or given up, the robot's attempt under way ends without a result, so the next
    trial counts from the next departure from A (only when nobody else drives the robot; an offline robot keeps
    its run, and the page then says a run that began before the trial will not count)."""
    if not services.may_restart_run(session, _actor(), trial.robot_name):
        return
    robot_name = trial.robot_name

    def restart() -> None:
        link = robot_registry().get(robot_name)
        try:
            if link is not None:
                link.restart_track_run()
        except (RobotUnavailable, CommandRefused) as error:
            log.warning("the track run of %s was not restarted: %s", robot_name, error)

    after_commit(restart)


def _stop_motor_goal_after_commit(trial: Trial) -> None:
    """Once the trial is begun, a go-to-goal or plan its student started before stops (a zero drive preempts any
    motor goal): from then on the student drives by hand, and the command path refuses the rest."""
    robot_name, user_id = trial.robot_name, trial.user_id

    def stop() -> None:
        robot = robot_commands().for_user(robot_name, user_id)
        try:
            if robot.is_controller():
                robot.stop()
        except (RobotUnavailable, CommandRefused) as error:
            log.warning("%s was not stopped at the start of a trial: %s", robot_name, error)

    after_commit(stop)


def _run_progress(trial: Trial) -> dict[str, object]:
    """The trial's run as the page shows it while the student drives."""
    try:
        run = _track_run_now(robot_registry().get(trial.robot_name))
    except RobotUnavailable:
        run = None
    if run is None:
        return {"online": False, "finished": False,
                "message": gettext("The robot %(robot)s does not answer right now; its progress shows again when "
                                   "it does.", robot=trial.robot_name)}
    return progress_view(trial, run)


def _set_feedback_preference(session: Session, user_id: int, enabled: bool) -> None:
    """The trial's condition becomes the console's motion-preview setting."""
    row = session.scalar(select(UserPreference).where(UserPreference.user_id == user_id,
                                                      UserPreference.key == FEEDBACK_PREFERENCE_KEY))
    value = json.dumps(enabled)
    if row is None:
        session.add(UserPreference(user_id=user_id, key=FEEDBACK_PREFERENCE_KEY, value_json=value))
    else:
        row.value_json, row.updated_at = value, utc_now()


@blueprint.get("/experiment")
@login_required
def page() -> ResponseReturnValue:
    """Students run trials; tutors set delays and read the results."""
    return render_template("experiment/experiment.html", is_teacher=current_user.role in ("tutor", "admin"))


@blueprint.get("/api/experiment/state")
@login_required
@described(answers={200: STATE})
def state() -> ResponseReturnValue:
    """The student's trial in progress with its run now, their video delay (the trial's, on its robot; else a
    tutor's), their last trial ended (recorded or given up), and, while no trial is in progress, the robots that
    run a track and the courses a trial may count for (the page polls this at 2 Hz during a trial)."""
    session = get_session()
    actor = _actor()
    trial = services.current_trial(session, actor)
    last = services.last_finished_trial(session, actor)
    courses = services.student_courses(session, actor)
    return jsonify({
        "protocol": protocol.state_for(session, actor, trial.course_id if trial else
                                       (courses[0].id if courses else None)),
        "trial": _trial_dict(trial) if trial else None,
        "run": _run_progress(trial) if trial else None,
        "last_trial": _trial_dict(last) if last else None,
        "robots": track_robots(actor.id) if trial is None else [],
        "courses": [{"id": c.id, "code": c.code, "title": c.title} for c in courses] if trial is None else [],
        "delay_s": trial.delay_s if trial else services.get_video_delay(session, actor.id),
    })


@blueprint.post("/api/experiment/trials")
@login_required
@described(
    body=obj(robot_name=about("a robot running a course scene"), course_id=about("the course it counts for")),
    body_required=False,
    answers={201: obj(("trial",), trial=OBJECT)},
    refusals=(409, 503),
)
def start_trial() -> ResponseReturnValue:
    """Assigns a random condition on the chosen track robot and applies its delay and feedback setting."""
    body = request.get_json(silent=True) or {}
    robot_name = body.get("robot_name")
    robots = {str(r["name"]): str(r["scene"]) for r in track_robots(int(current_user.get_id()))}
    if not isinstance(robot_name, str) or robot_name not in robots:
        raise ApiError(400, "invalid_field", gettext("Choose a robot that runs a course scene."), "robot_name")

    def action(session: Session) -> Trial:
        open_before = services.current_trial(session, _actor())
        trial = services.assign_trial(session, _actor(), robot_name, robots[robot_name],
                                      course_id=body.get("course_id"))
        _set_feedback_preference(session, trial.user_id, trial.feedback)
        if open_before is None:
            _restart_run_after_commit(session, trial)
            _stop_motor_goal_after_commit(trial)
        return trial

    return jsonify({"trial": _trial_dict(_run(action))}), 201


@blueprint.put("/api/experiment/participant")
@login_required
@described(
    body=obj(
        ("consent",),
        consent=about("true or false"),
        age=about("years"),
        location=about("where"),
        games_experience=about("a level"),
        robots_experience=about("a level"),
    ),
    answers={200: PARTICIPANT},
    refusals=(409,),
)
def put_participant() -> ResponseReturnValue:
    """The student's details, asked once before the first trial: {"consent": bool, "age", "location",
    "games_experience", "robots_experience"} (kept only with consent)."""
    body = _json_object()
    row = protocol.answer_details(get_session(), _actor(), body)
    return jsonify({"consent": row.consent, "age": row.age, "location": row.location,
                    "games_experience": row.games_experience, "robots_experience": row.robots_experience})


@blueprint.post("/api/experiment/learning")
@login_required
@described(answers={201: obj(("started",), started=BOOLEAN)}, refusals=(409,))
def start_learning() -> ResponseReturnValue:
    """Starts the student's learning period (time to drive the course freely before the first trial)."""
    protocol.start_learning(get_session(), _actor())
    return jsonify({"started": True}), 201


@blueprint.get("/api/experiment/protocols")
@login_required
@described(answers={200: obj(("courses",), courses=array(OBJECT))})
def protocols() -> ResponseReturnValue:
    """The courses the tutor teaches (every course for an admin) with their experiment protocol."""
    session = get_session()
    actor = _actor()
    if actor.role not in ("tutor", "admin"):
        raise ApiError(403, "forbidden", gettext("Only tutors and admins set experiment protocols."))
    query = select(Course).order_by(Course.code)
    if actor.role != "admin":
        query = query.where(Course.id.in_(taught_course_ids(actor)))
    return jsonify({"courses": [{"id": c.id, "code": c.code, "title": c.title,
                                 **protocol.protocol_for(session, c.id).__dict__}
                                for c in session.scalars(query)]})


@blueprint.put("/api/experiment/protocols/<int:course_id>")
@login_required
@described(
    body=obj(
        learning_s=about("seconds"), delay_commands=about("true or false"), export_participants=about("true or false")
    ),
    answers={200: obj(("course_id",), course_id=ID)},
)
def put_protocol(course_id: int) -> ResponseReturnValue:
    """A tutor sets the course's learning period and switches: {"learning_s", "delay_commands",
    "export_participants"} (any of them)."""
    settings = protocol.set_protocol(get_session(), _actor(), course_id, _json_object())
    return jsonify({"course_id": course_id, **settings.__dict__})


@blueprint.post("/api/experiment/trials/<int:trial_id>/finish")
@login_required
@described(answers={200: obj(("trial",), trial=OBJECT)}, refusals=(409, 503))
def finish(trial_id: int) -> ResponseReturnValue:
    """Records the run the robot's track monitor finished after the trial began."""
    session = get_session()
    trial = session.get(Trial, trial_id)
    if trial is None or trial.user_id != int(current_user.get_id()):
        raise ApiError(404, "unknown_trial", gettext("There is no such trial of yours."), "trial_id")
    if trial.status == TRIAL_OPEN and not robot_commands().for_user(trial.robot_name, trial.user_id).is_controller():
        raise ApiError(403, "not_controller", gettext("Only the person driving %(robot_name)s can record its run: "
                                                      "take your turn in its console and drive the course yourself.",
                                                      robot_name=trial.robot_name))
    run = _track_run_now(robot_registry().get(trial.robot_name))
    if run is None or not finished_in_trial(trial, run):
        raise ApiError(409, "run_not_finished", gettext("The robot has not seen you finish the course since this "
                                                        "trial began. Drive from %(track_route)s first.",
                                                        track_route=track_route(trial)))
    result = services.RunResult(run.last_total_time_s, run.last_errors)
    return jsonify({"trial": _trial_dict(_run(lambda s: services.finish_trial(s, _actor(), trial_id, result)))})


@blueprint.post("/api/experiment/trials/<int:trial_id>/abandon")
@login_required
@described(answers={200: obj(("trial",), trial=OBJECT)}, refusals=(409,))
def abandon(trial_id: int) -> ResponseReturnValue:
    """Gives the trial up; it is not counted, and the robot's run under way ends with it."""

    def action(session: Session) -> Trial:
        trial = services.abandon_trial(session, _actor(), trial_id)
        _restart_run_after_commit(session, trial)
        return trial

    return jsonify({"trial": _trial_dict(_run(action))})


@blueprint.put("/api/experiment/delays/<username>")
@login_required
@described(
    body=obj(("delay_s",), delay_s=about("0 to 7 seconds")),
    answers={200: obj(("username", "delay_s"), username=STRING, delay_s=number())},
)
def put_delay(username: str) -> ResponseReturnValue:
    """A tutor sets one user's added video delay: {"delay_s": 0..7}."""
    body = request.get_json(silent=True)
    if not isinstance(body, dict) or "delay_s" not in body:
        raise ApiError(400, "invalid_field", gettext("Send a JSON object with delay_s."), "delay_s")
    session = get_session()
    user = session.scalar(select(User).where(User.username == username.lower()))
    user_id = user.id if user is not None else -1
    row = _run(lambda s: services.set_video_delay(s, _actor(), user_id, body["delay_s"]))
    return jsonify({"username": username.lower(), "delay_s": row.delay_s})


@blueprint.get("/api/experiment/results")
@login_required
@described(answers={200: RESULTS})
def results() -> ResponseReturnValue:
    """Every completed trial and the means with standard errors per condition (tutors)."""
    rows = _run(lambda s: services.class_trials(s, _actor()))
    summary = services.summarise(trial for trial, _ in rows)
    return jsonify({
        "trials": [{**_trial_dict(t), "username": name} for t, name in rows],
        "summary": [g.__dict__ for g in summary],
        "comparisons": [c.__dict__ for c in services.compare(summary)],
        "participants": protocol.participants_summary(get_session(), _class_student_ids()),
        "orders": len(protocol.ORDERS),
    })


def _class_student_ids() -> set[int]:
    """The students of the courses the actor teaches (every student for an admin)."""
    actor = _actor()
    query = select(CourseMembership.user_id).where(CourseMembership.role == "student")
    if actor.role != "admin":
        query = query.where(CourseMembership.course_id.in_(taught_course_ids(actor)))
    return set(get_session().scalars(query))


@blueprint.get("/experiment/results.csv")
@login_required
def results_csv() -> ResponseReturnValue:
    """The class's trials as CSV."""
    rows = _run(lambda s: services.class_trials(s, _actor()))
    details = services.exportable_details(get_session(), rows)
    return Response(services.results_csv(rows, details), mimetype="text/csv",
                    headers={"Content-Disposition": "attachment; filename=experiment-results.csv"})
