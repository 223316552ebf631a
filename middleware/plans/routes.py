"""Plans pages and API: list, write and check, save as versions, copy, share, export, import, and run on a robot.

Routes parse and respond; middleware.plans.services decides who may do what, middleware.plans.runs sends a plan
to a robot. Plans are checked against the skills of a robot that answers (the user's practice robot, else any lab
robot): with none answering, saving is refused with a sentence (503 no_robot_to_check).
"""

from __future__ import annotations

from collections.abc import Iterator

from flask import Blueprint, Flask, Response, abort, current_app, jsonify, render_template, request
from flask.typing import ResponseReturnValue
from flask_babel import force_locale, gettext  # type: ignore[import-untyped]
from flask_login import current_user, login_required

from middleware import i18n
from middleware.access.limits import WATCHDOG_FIELD, changeable_fields
from middleware.api.contract import (
    ANY,
    BOOLEAN,
    ID,
    OBJECT,
    STRING,
    about,
    array,
    described,
    file_answer,
    nullable,
    obj,
    one_of,
    text,
    whole,
)
from middleware.auth.schemas import InvalidField
from middleware.courses.services import list_courses
from middleware.db import after_commit, get_session
from middleware.models import Role
from middleware.plans import schemas, services
from middleware.plans.language import PlanInvalid, plan_from_json
from middleware.plans.predictions import PredictionRequest, prediction_slots, prediction_stream
from middleware.plans.runs import RunRequest, check_settings_permitted, lab_robot_now, run_plan
from middleware.plans.services import PlanRefused
from middleware.robots.registry import robot_registry
from middleware.teaching.practice_robots import practice_manager
from middleware.teaching.targets import reference_skills
from middleware.web import json_body

blueprint = Blueprint("plans", __name__)


def _skills() -> dict[str, list[dict[str, object]]]:
    return reference_skills(current_user.id, motor_only=True)


def _may_set_watchdog() -> bool:
    return WATCHDOG_FIELD in changeable_fields(get_session(), current_user)


def _plan_answer(plan_id: int, status: int = 200, version: int | None = None) -> ResponseReturnValue:
    dbs = get_session()
    plan = services.readable_plan(dbs, current_user, plan_id)
    return jsonify({"plan": services.plan_dict(dbs, current_user, plan, services.plan_version(dbs, plan, version))}), \
        status


# --- pages ----------------------------------------------------------------------------------------


@blueprint.get("/plans")
@login_required
def index() -> ResponseReturnValue:
    """My plans and the plans shared with my courses, with New and Import."""
    return render_template("plans/index.html")


@blueprint.get("/plans/<int:plan_id>")
@login_required
def editor(plan_id: int) -> ResponseReturnValue:
    """The plan's editor: write, check, save, copy, share, export; try it on the practice robot or run it."""
    dbs = get_session()
    try:
        plan = services.readable_plan(dbs, current_user, plan_id)
    except PlanRefused:
        abort(404)
    teaches = current_user.role in (Role.TUTOR, Role.ADMIN)
    courses = list_courses(dbs, current_user) if teaches else []
    lab_robots = robot_registry().names()
    return render_template("plans/editor.html", plan_id=plan.id, plan_name=plan.name,
                           mine=plan.owner_id == current_user.id, courses=courses, teaches=teaches,
                           lab_robots=lab_robots)


# --- JSON API -----------------------------------------------------------------------------------


@blueprint.get("/api/plans")
@login_required
@described(answers={200: obj(("plans",), plans=array(OBJECT))})
def api_list() -> ResponseReturnValue:
    """{"plans": [...]}: mine first, then those shared with my courses."""
    dbs = get_session()
    return jsonify({"plans": [services.plan_dict(dbs, current_user, plan)
                              for plan in services.visible_plans(dbs, current_user)]})


@blueprint.post("/api/plans/check")
@login_required
@described(
    body=obj(("text",), text=text(description="the plan, one command a line")),
    answers={200: obj(("valid", "errors"), valid=BOOLEAN, errors=array(OBJECT), summary=ANY, plan=ANY)},
    refusals=(503,),
)
def api_check() -> ResponseReturnValue:
    """Checks a plan's text: {"valid", "errors": [{line, column, field, message}], "summary", "plan"}."""
    text = schemas.plan_text(json_body().get("text"))
    try:
        checked = services.check_text(text, _skills())
    except PlanInvalid as invalid:
        return jsonify({"valid": False, "errors": [error.to_dict() for error in invalid.errors],
                        "summary": None, "plan": None})
    return jsonify({"valid": True, "errors": [], "summary": checked.summary(), "plan": checked.document()})


@blueprint.post("/api/plans")
@login_required
@described(
    body=obj(
        ("name", "text"),
        name=text(64, description="1 to 64 letters, digits, - and _"),
        text=text(description="the plan, one command a line"),
    ),
    answers={201: obj(("plan",), plan=OBJECT)},
    refusals=(503,),
)
def api_create() -> ResponseReturnValue:
    """Creates a plan from {"name", "text"}; 201 with it, or 400 invalid_plan listing every error."""
    body = json_body()
    name = schemas.plan_name(body.get("name"))
    checked = services.check_text(schemas.plan_text(body.get("text")), _skills())
    plan = services.create_plan(get_session(), current_user, name, checked)
    return _plan_answer(plan.id, 201)


@blueprint.get("/api/plans/<int:plan_id>")
@login_required
@described(query={"version": whole(1, 2**31 - 1)}, answers={200: obj(("plan",), plan=OBJECT)})
def api_read(plan_id: int) -> ResponseReturnValue:
    """A plan with its latest version, or ?version=N."""
    return _plan_answer(plan_id, version=schemas.optional_version(request.args.get("version")))


@blueprint.put("/api/plans/<int:plan_id>")
@login_required
@described(
    body=obj(("text",), text=text(description="the plan, one command a line"), name=nullable(text(64))),
    answers={200: obj(("plan",), plan=OBJECT)},
    refusals=(503,),
)
def api_save(plan_id: int) -> ResponseReturnValue:
    """Saves {"text", "name"?} as the plan's next version."""
    body = json_body()
    services.owned_plan(get_session(), current_user, plan_id)  # who may, before what was sent
    name = schemas.plan_name(body["name"]) if body.get("name") is not None else None
    checked = services.check_text(schemas.plan_text(body.get("text")), _skills())
    services.save_plan(get_session(), current_user, plan_id, checked, name)
    return _plan_answer(plan_id)


@blueprint.delete("/api/plans/<int:plan_id>")
@login_required
@described(answers={200: obj(("deleted",), deleted=ID)})
def api_delete(plan_id: int) -> ResponseReturnValue:
    """Deletes my plan and its versions."""
    services.delete_plan(get_session(), current_user, plan_id)
    return jsonify({"deleted": plan_id})


@blueprint.post("/api/plans/<int:plan_id>/copy")
@login_required
@described(body=obj(name=nullable(text(64))), body_required=False, answers={201: obj(("plan",), plan=OBJECT)})
def api_copy(plan_id: int) -> ResponseReturnValue:
    """Copies a plan I may read into my plans ({"name"?}); 201 with the copy."""
    body = request.get_json(silent=True)
    raw_name = body.get("name") if isinstance(body, dict) else None
    name = schemas.plan_name(raw_name) if raw_name not in (None, "") else None
    copy = services.copy_plan(get_session(), current_user, plan_id, name)
    return _plan_answer(copy.id, 201)


@blueprint.put("/api/plans/<int:plan_id>/share")
@login_required
@described(
    body=obj(("course_id",), course_id=about("a course's id, or null")), answers={200: obj(("plan",), plan=OBJECT)}
)
def api_share(plan_id: int) -> ResponseReturnValue:
    """Shares my plan with a course I teach ({"course_id": id}) or stops sharing it ({"course_id": null})."""
    body = json_body()
    if "course_id" not in body:
        raise InvalidField("course_id", gettext("course_id must be a course's id or null."))
    services.share_plan(get_session(), current_user, plan_id, schemas.optional_course_id(body["course_id"]))
    return _plan_answer(plan_id)


@blueprint.put("/api/plans/<int:plan_id>/skill")
@login_required
@described(body=obj(("console_skill",), console_skill=BOOLEAN), answers={200: obj(("plan",), plan=OBJECT)})
def api_use_as_skill(plan_id: int) -> ResponseReturnValue:
    """Shows my plan as a panel in my consoles ({"console_skill": true}) or stops ({"console_skill": false})."""
    body = json_body()
    if not isinstance(body.get("console_skill"), bool):
        raise InvalidField("console_skill", gettext("%(field)s must be true or false.", field="console_skill"))
    services.use_as_skill(get_session(), current_user, plan_id, bool(body["console_skill"]))
    return _plan_answer(plan_id)


@blueprint.get("/api/plans/<int:plan_id>/export")
@login_required
@described(
    query={"format": one_of("json", "txt"), "version": whole(1, 2**31 - 1)},
    answers={200: file_answer("application/json", "the plan as a file (text/plain with ?format=txt)",
                              {"text/plain": {"type": "string"}},
                              schema=obj(("format", "steps"), description="the canonical form (json_form.py)",
                                         format=STRING, steps=array(OBJECT)))},
)
def api_export(plan_id: int) -> ResponseReturnValue:
    """The plan as a file: ?format=json (canonical, the default) or txt; ?version=N for an older one."""
    chosen = schemas.export_format(request.args.get("format"))
    dbs = get_session()
    plan = services.readable_plan(dbs, current_user, plan_id)
    version = services.plan_version(dbs, plan, schemas.optional_version(request.args.get("version")))
    if chosen == "txt":
        body, mimetype = version.text if version.text.endswith("\n") else version.text + "\n", "text/plain"
    else:
        body, mimetype = services.export_json(version), "application/json"
    response = Response(body, mimetype=mimetype)
    response.headers["Content-Disposition"] = f'attachment; filename="{plan.name}.{chosen}"'
    response.headers["X-Content-Type-Options"] = "nosniff"
    return response


@blueprint.post("/api/plans/import")
@login_required
@described(
    form=obj(
        ("file",), file={"type": "string", "format": "binary", "description": ".json (exported) or .txt"}, name=text(64)
    ),
    answers={201: obj(("plan",), plan=OBJECT)},
    refusals=(413, 503),
)
def api_import() -> ResponseReturnValue:
    """Imports a plan file (multipart "file", optional "name"); 201 with the new plan, or 400 naming the line."""
    upload = request.files.get("file")
    if upload is None or not upload.filename:
        raise InvalidField("file", gettext("Choose a plan file (.json or .txt) to import."))
    plan_file = schemas.read_plan_file(upload.filename, upload.read(schemas.MAX_JSON_FILE_BYTES + 1))
    raw_name = request.form.get("name")
    name = schemas.plan_name(raw_name) if raw_name else schemas.plan_name(plan_file.suggested_name, "file")
    checked = services.check_file(plan_file, _skills())
    plan = services.create_plan(get_session(), current_user, name, checked)
    return _plan_answer(plan.id, 201)


@blueprint.post("/api/plans/<int:plan_id>/runs")
@login_required
@described(
    body=obj(
        ("target",),
        target=text(64, description='"practice" or a lab robot'),
        beside=about("the lab robot it runs beside"),
        from_dock=BOOLEAN,
        version=about("a version, or the latest"),
    ),
    answers={202: obj(("plan_id", "version"), plan_id=ID, version=whole(1))},
    refusals=(409, 429, 503),
)
def api_run(plan_id: int) -> ResponseReturnValue:
    """Runs the plan ({"target": "practice" | robot name, "beside": lab robot, "from_dock": bool, "version"?}); a
    practice robot not running yet is claimed and started after the commit: 202 with starting true, run it again
    once GET /api/practice says it runs."""
    body = json_body()
    dbs = get_session()
    plan = services.readable_plan(dbs, current_user, plan_id)
    version = services.plan_version(dbs, plan, schemas.optional_version(body.get("version")))
    beside = body.get("beside")
    run = RunRequest(schemas.run_target(body.get("target")),
                     None if beside in (None, "") else schemas.run_target(beside, "beside"),
                     schemas.flag(body.get("from_dock"), "from_dock"))
    ran = run_plan(dbs, current_user.id, current_user.username, plan.name, services.stored_document(version), run,
                   _may_set_watchdog())
    if ran.pending is not None:  # the practice robot starts once its claim is committed; the page runs again then
        after_commit(ran.pending.run_quietly)
    return jsonify({**ran.answer, "plan_id": plan.id, "version": version.version}), 202


def _in_language(lines: Iterator[bytes], app: Flask, language: str) -> Iterator[bytes]:
    """lines, said in the request's language: a stream runs after its request has ended (as Flask's
    stream_with_context keeps the request, this keeps an app context and the language for it)."""
    with app.app_context(), force_locale(language):
        yield from lines


@blueprint.post("/api/plans/<int:plan_id>/predictions")
@login_required
@described(
    body=obj(beside=about("the lab robot to copy"), from_dock=BOOLEAN, version=about("a version, or the latest")),
    answers={200: file_answer("application/x-ndjson", "the prediction's progress, a JSON object a line")},
    refusals=(409, 503),
)
def api_predict(plan_id: int) -> ResponseReturnValue:
    """Predicts the plan in fast mode on a throwaway copy of a lab robot ({"beside": lab robot, "from_dock": bool,
    "version"?}): a stream of JSON lines (application/x-ndjson), progress then the end (middleware.plans.predictions).
    What the request gets wrong is refused as JSON before the stream starts."""
    body = json_body()
    dbs = get_session()
    plan = services.readable_plan(dbs, current_user, plan_id)
    version = services.plan_version(dbs, plan, schemas.optional_version(body.get("version")))
    beside_name = body.get("beside")
    beside_name = None if beside_name in (None, "") else schemas.run_target(beside_name, "beside")
    from_dock = schemas.flag(body.get("from_dock"), "from_dock")
    document = services.stored_document(version)
    check_settings_permitted(plan_from_json(document, _skills()), _may_set_watchdog())
    app = current_app._get_current_object()  # type: ignore[attr-defined]
    slots = prediction_slots(app)
    slots.check(current_user.id)
    beside = lab_robot_now(beside_name, current_user.id) if beside_name else None
    manager = practice_manager()
    prediction = PredictionRequest(current_user.id, plan.name, document, (beside.scene if beside else None)
                                   or manager.scene, beside, from_dock)
    response = Response(_in_language(prediction_stream(manager.farm, slots, prediction), app,
                                     i18n.current_language()), mimetype="application/x-ndjson")
    response.headers["Cache-Control"] = "no-store"
    response.headers["X-Accel-Buffering"] = "no"  # nginx passes each line on as it comes
    return response
