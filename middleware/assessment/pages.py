"""Assessment pages: the tutor's bank and tests, attempts and review; the student's tests, attempts, survey."""

from __future__ import annotations

from dataclasses import replace
from datetime import UTC
from typing import Any

from flask import Blueprint, Response, abort, flash, redirect, render_template, request, url_for
from flask_login import current_user, login_required
from sqlalchemy import select

from middleware.accounts.services import Refused
from middleware.assessment import attempts, bank, recommendations, review, survey
from middleware.assessment.attempts import TimeUp, window_state
from middleware.assessment.routes import controls_robot, finish_recording, server_now, start_recording
from middleware.assessment.schemas import AGREEMENT, SURVEY_ITEMS, parse_exam, parse_question, parse_survey
from middleware.auth.schemas import InvalidField
from middleware.courses.services import list_courses
from middleware.db import get_session
from middleware.models import Course

blueprint = Blueprint("assessment_pages", __name__)
CSS = "css/assessment.css"


def _refused(error: Refused) -> None:
    get_session().rollback()
    abort(error.status if error.status in (403, 404) else 409)


def _form_answers() -> dict[str, Any]:
    answers: dict[str, Any] = {}
    for key in request.form:
        if key.startswith("q-"):
            values = request.form.getlist(key)
            item = key[2:]
            if item.endswith("-unit"):
                answers.setdefault(item[:-5], {})["unit"] = values[0]
            elif item.endswith("-value"):
                answers.setdefault(item[:-6], {})["value"] = values[0]
            elif item.endswith("-many"):
                answers[item[:-5]] = values
            else:
                answers[item] = values[0]
    for name in ("report-x_m", "report-y_m"):
        if request.form.get(name, "").strip():
            answers.setdefault("report", {})[name[7:]] = request.form[name]
    return answers


@blueprint.get("/assessment")
@login_required
def hub():  # type: ignore[no-untyped-def]
    """Students: their tests (open now, upcoming, done) and recommendations; tutors: the courses they assess."""
    dbs, now = get_session(), server_now()
    attempts.settle_due(dbs, now, user_id=current_user.id)
    courses = []
    for view in list_courses(dbs, current_user):
        entry: dict[str, Any] = {"course": view, "teaches": bank.may_teach(dbs, current_user, view.id)}
        if not entry["teaches"] and view.my_role == "student":
            groups: dict[str, list[Any]] = {"open": [], "upcoming": [], "done": []}
            for exam in bank.list_exams(dbs, view.id):
                mine = attempts.my_attempts(dbs, current_user.id, exam.id)
                state = window_state(exam, now)
                used_up = exam.max_attempts is not None and len(mine) >= exam.max_attempts \
                    and all(a.status == "submitted" for a in mine)
                key = "done" if state == "closed" or used_up else state
                groups[key].append({"exam": exam, "attempts": mine})
            entry["groups"] = groups
            entry["topics"] = recommendations.topic_scores(dbs, current_user.id, view.id)
            entry["recommendations"] = recommendations.recommend(dbs, current_user.id, view.id, now)
            entry["answered_survey"] = survey.has_answered(dbs, current_user.id, view.id)
        courses.append(entry)
    dbs.commit()
    return render_template("assessment/hub.html", courses=courses, css=CSS, now=now)


def _moment_field(moment: Any) -> str:
    """A stored UTC moment as a datetime-local value (seconds only when there are some)."""
    if moment is None:
        return ""
    moment = moment.astimezone(UTC) if moment.tzinfo else moment
    return moment.strftime("%Y-%m-%dT%H:%M:%S" if moment.second else "%Y-%m-%dT%H:%M")


def _question_form(question: Any) -> dict[str, Any]:
    """The bank editor's fields for a stored question."""
    spec = question.spec
    correct = spec.get("correct")
    return {"kind": question.kind, "prompt": question.prompt, "topics": ", ".join(question.topics),
            "points": f"{question.points:g}", "choices": "\n".join(spec.get("choices", [])),
            "correct": ", ".join(map(str, correct)) if isinstance(correct, list) else str(correct or 0)
            if "choices" in spec else "",
            "value": repr(spec["value"]) if "value" in spec else "",
            "tolerance": repr(spec["tolerance"]) if "tolerance" in spec else "",
            "unit": spec.get("unit", ""), "accepted": "\n".join(spec.get("accepted", [])),
            "case_sensitive": "1" if spec.get("case_sensitive") else ""}


TASK_FIELDS = ("x_m", "y_m", "x1_m", "y1_m", "x2_m", "y2_m", "distance_m", "min_travel_m")


def _exam_form(exam: Any) -> dict[str, Any]:
    """The test editor's fields for a stored exam (the task's too)."""
    form: dict[str, Any] = {
        "title": exam.title, "kind": exam.kind, "opens_at": _moment_field(exam.opens_at),
        "closes_at": _moment_field(exam.closes_at), "duration_s": exam.duration_s or "",
        "max_attempts": exam.max_attempts or "", "question_ids": [str(i) for i in exam.question_ids or []],
        "robot_name": exam.robot_name or "lab-1"}
    task = exam.task or {}
    if task:
        form.update({"task_kind": task["kind"], "task_points": repr(task.get("points", 10)),
                     "task_topics": ", ".join(task.get("topics") or []), "instructions": task.get("instructions", ""),
                     "rubric": ", ".join(f"{bound!r}:{share!r}" for bound, share in task.get("rubric") or [])})
        form.update({name: repr(task[name]) for name in TASK_FIELDS if name in task})
    return form


def _course_page(course_id: int, status: int = 200, errors: dict[str, str] | None = None,
                 form: dict[str, Any] | None = None, editing: tuple[str, int] | None = None,
                 error_key: str = ""):  # type: ignore[no-untyped-def]
    """The tutor's page; editing ("question" | "exam", id) opens that item's edit form (prefilled unless form)."""
    dbs, now = get_session(), server_now()
    try:
        course = bank.teaching_course(dbs, current_user, course_id)
        questions = bank.list_questions(dbs, current_user, course_id)
    except Refused as refused:
        _refused(refused)
    exam_rows = bank.list_exams(dbs, course_id)
    exams = [{**review.exam_dict(e, now), "has_attempts": bank.has_attempts(dbs, e.id)} for e in exam_rows]
    qform: dict[str, Any] = dict(form or {}) if error_key == "question" else {}
    eform: dict[str, Any] = dict(form or {}) if error_key == "exam" else {}
    edit_question = edit_exam = None
    if editing and editing[0] == "question":
        edit_question = next((q for q in questions if q.id == editing[1]), None)
        if edit_question is None:
            abort(404)
        qform = qform or _question_form(edit_question)
    elif editing and editing[0] == "exam":
        edit_exam = next((e for e in exams if e["id"] == editing[1]), None)
        if edit_exam is None:
            abort(404)
        eform = eform or _exam_form(next(e for e in exam_rows if e.id == editing[1]))
    if isinstance(eform.get("question_ids"), str):
        eform["question_ids"] = [eform["question_ids"]]
    return render_template("assessment/course.html", course=course, questions=questions, exams=exams,
                           errors=errors or {}, qform=qform, eform=eform, edit_question=edit_question,
                           edit_exam=edit_exam, css=CSS), status


@blueprint.get("/courses/<int:course_id>/assessment")
@login_required
def course_page(course_id: int):  # type: ignore[no-untyped-def]
    """The tutor's bank editor, tests, grades export and survey results for a course; ?question=<id> or ?exam=<id>
    opens that question's or test's edit form."""
    for kind in ("question", "exam"):
        wanted = request.args.get(kind, "")
        if wanted.isdigit():
            return _course_page(course_id, editing=(kind, int(wanted)))
    return _course_page(course_id)


def _course_action(course_id: int, action, success: str, error_key: str,  # type: ignore[no-untyped-def]
                   editing: tuple[str, int] | None = None, keep_form: bool = True):
    """Runs a form's action; on a refusal, the page again with the message (and the form as sent, if keep_form)."""
    dbs, form = get_session(), request.form.to_dict()
    if error_key == "exam":
        form["question_ids"] = request.form.getlist("question_ids")  # type: ignore[assignment]
    try:
        bank.teaching_course(dbs, current_user, course_id)
        action(dbs, form)
    except Refused as refused:
        if refused.status in (403, 404):
            _refused(refused)
        dbs.rollback()
        return _course_page(course_id, refused.status, {error_key: refused.message}, form if keep_form else None,
                            editing, error_key)
    except InvalidField as invalid:
        dbs.rollback()
        return _course_page(course_id, 400, {error_key: f"{invalid.field}: {invalid.message}"}, form, editing,
                            error_key)
    dbs.commit()
    flash(success, "success")
    return redirect(url_for("assessment_pages.course_page", course_id=course_id), 303)


def _own_question(dbs: Any, course_id: int, question_id: int) -> Any:
    question = bank.course_question(dbs, current_user, question_id)
    if question.course_id != course_id:
        raise Refused(404, "unknown_question", f"There is no question with id {question_id} here.", "question_id")
    return question


def _own_exam(dbs: Any, course_id: int, exam_id: int) -> Any:
    exam = bank.managed_exam(dbs, current_user, exam_id)
    if exam.course_id != course_id:
        raise Refused(404, "unknown_exam", f"There is no test with id {exam_id} here.", "exam_id")
    return exam


@blueprint.post("/courses/<int:course_id>/assessment/questions")
@login_required
def add_question(course_id: int):  # type: ignore[no-untyped-def]
    """Adds a question from the bank editor's form."""
    return _course_action(course_id, lambda dbs, form: bank.add_question(dbs, current_user, course_id,
                                                                         parse_question(form)),
                          "Question added to the bank.", "question")


@blueprint.post("/courses/<int:course_id>/assessment/questions/<int:question_id>")
@login_required
def edit_question(course_id: int, question_id: int):  # type: ignore[no-untyped-def]
    """Replaces a question from its edit form (attempts already graded keep their marks)."""
    def action(dbs, form):  # type: ignore[no-untyped-def]
        _own_question(dbs, course_id, question_id)
        bank.update_question(dbs, current_user, question_id, parse_question(form))

    return _course_action(course_id, action, f"Question #{question_id} saved.", "question",
                          ("question", question_id))


@blueprint.post("/courses/<int:course_id>/assessment/questions/<int:question_id>/delete")
@login_required
def delete_question(course_id: int, question_id: int):  # type: ignore[no-untyped-def]
    """Removes a question from the bank (and from the tests nobody has attempted)."""
    def action(dbs, _form):  # type: ignore[no-untyped-def]
        _own_question(dbs, course_id, question_id)
        bank.delete_question(dbs, current_user, question_id)

    return _course_action(course_id, action, f"Question #{question_id} deleted.", "question",
                          ("question", question_id), keep_form=False)


@blueprint.post("/courses/<int:course_id>/assessment/bank")
@login_required
def import_bank(course_id: int):  # type: ignore[no-untyped-def]
    """Imports a bank file (JSON)."""
    def action(dbs, _form):  # type: ignore[no-untyped-def]
        upload = request.files.get("file")
        if upload is None or not upload.filename:
            raise InvalidField("file", "Choose a question bank file (JSON) to import.")
        bank.import_bank(dbs, current_user, course_id, upload.read())

    return _course_action(course_id, action, "Question bank imported.", "file")


@blueprint.post("/courses/<int:course_id>/assessment/exams")
@login_required
def create_exam(course_id: int):  # type: ignore[no-untyped-def]
    """Creates a quiz or a timed test from the test editor's form."""
    return _course_action(course_id, lambda dbs, form: bank.create_exam(dbs, current_user, course_id,
                                                                        parse_exam(form)), "Test created.", "exam")


@blueprint.post("/courses/<int:course_id>/assessment/exams/<int:exam_id>")
@login_required
def edit_exam(course_id: int, exam_id: int):  # type: ignore[no-untyped-def]
    """Changes a test from its edit form (only its title and times once someone has started it)."""
    def action(dbs, form):  # type: ignore[no-untyped-def]
        exam = _own_exam(dbs, course_id, exam_id)
        data = parse_exam(form)
        if set(data.question_ids) == set(exam.question_ids or []):  # the checkboxes' order is the bank's
            data = replace(data, question_ids=list(exam.question_ids))
        bank.update_exam(dbs, current_user, exam_id, data)

    return _course_action(course_id, action, "Test saved.", "exam", ("exam", exam_id))


@blueprint.post("/courses/<int:course_id>/assessment/exams/<int:exam_id>/delete")
@login_required
def delete_exam(course_id: int, exam_id: int):  # type: ignore[no-untyped-def]
    """Deletes a test nobody has attempted; a test with attempts is refused with the reason."""
    def action(dbs, _form):  # type: ignore[no-untyped-def]
        _own_exam(dbs, course_id, exam_id)
        bank.delete_exam(dbs, current_user, exam_id)

    return _course_action(course_id, action, "Test deleted.", "exam", ("exam", exam_id), keep_form=False)


@blueprint.get("/assessment/exams/<int:exam_id>")
@login_required
def exam_page(exam_id: int):  # type: ignore[no-untyped-def]
    """A student's start page for an exam, or the tutor's list of attempts."""
    dbs, now = get_session(), server_now()
    try:
        exam = bank.get_exam(dbs, exam_id)
        teaches = bank.may_teach(dbs, current_user, exam.course_id)
        if not teaches:
            bank.student_course(dbs, current_user, exam.course_id)
        rows = review.list_attempts(dbs, current_user, exam_id, now) if teaches else None
        mine = None if teaches else attempts.my_attempts(dbs, current_user.id, exam_id)
    except Refused as refused:
        _refused(refused)
    dbs.commit()
    return render_template("assessment/exam.html", exam=review.exam_dict(exam, now), rows=rows, mine=mine,
                           teaches=teaches, course=dbs.get(Course, exam.course_id), css=CSS)


@blueprint.post("/assessment/exams/<int:exam_id>/start")
@login_required
def start(exam_id: int):  # type: ignore[no-untyped-def]
    """Starts (or resumes) the student's attempt and opens it."""
    dbs = get_session()
    try:
        bank.get_exam(dbs, exam_id)
        exam = bank.get_exam(dbs, exam_id)
        bank.student_course(dbs, current_user, exam.course_id)
        attempt = attempts.start_attempt(dbs, current_user, exam_id, server_now(), controls_robot)
    except Refused as refused:
        if refused.status in (403, 404):
            _refused(refused)
        dbs.rollback()
        flash(refused.message, "error")
        return redirect(url_for("assessment_pages.exam_page", exam_id=exam_id), 303)
    dbs.commit()
    if exam.kind == "experimental" and exam.robot_name:
        start_recording(attempt.id, exam.robot_name)
    return redirect(url_for("assessment_pages.attempt_page", attempt_id=attempt.id), 303)


@blueprint.get("/assessment/attempts/<int:attempt_id>")
@login_required
def attempt_page(attempt_id: int):  # type: ignore[no-untyped-def]
    """Taking an attempt (its student), the corrected attempt, or the tutor's review."""
    dbs = get_session()
    try:
        view = review.attempt_view(dbs, current_user, attempt_id, server_now())
        exam = bank.get_exam(dbs, view["exam"]["id"])
        teaches = bank.may_teach(dbs, current_user, exam.course_id)
    except Refused as refused:
        _refused(refused)
    dbs.commit()
    owner = attempts.get_attempt(dbs, attempt_id).user_id == current_user.id
    return render_template("assessment/attempt.html", a=view, teaches=teaches, owner=owner, css=CSS,
                           questions={str(q["id"]): q for q in view["questions"]}), 200, {"Cache-Control": "no-store"}


@blueprint.post("/assessment/attempts/<int:attempt_id>/submit")
@login_required
def submit(attempt_id: int):  # type: ignore[no-untyped-def]
    """Submits the attempt with the form's answers (without JavaScript, too)."""
    dbs = get_session()
    try:
        owner = attempts.get_attempt(dbs, attempt_id)
        trace = finish_recording(attempt_id) if owner.user_id == current_user.id else None
        attempts.submit_attempt(dbs, current_user, attempt_id, server_now(), _form_answers(), trace)
    except TimeUp as late:
        dbs.commit()
        flash(late.message, "warning")
        return redirect(url_for("assessment_pages.attempt_page", attempt_id=attempt_id), 303)
    except Refused as refused:
        if refused.status in (403, 404):
            _refused(refused)
        dbs.rollback()
        flash(refused.message, "error")
        return redirect(url_for("assessment_pages.attempt_page", attempt_id=attempt_id), 303)
    dbs.commit()
    flash("Submitted. Your corrected attempt is below.", "success")
    return redirect(url_for("assessment_pages.attempt_page", attempt_id=attempt_id), 303)


def _review_action(attempt_id: int, action, success: str):  # type: ignore[no-untyped-def]
    dbs = get_session()
    try:
        action(dbs, request.form)
    except Refused as refused:
        if refused.status in (403, 404):
            _refused(refused)
        dbs.rollback()
        flash(refused.message, "error")
        return redirect(url_for("assessment_pages.attempt_page", attempt_id=attempt_id), 303)
    dbs.commit()
    flash(success, "success")
    return redirect(url_for("assessment_pages.attempt_page", attempt_id=attempt_id), 303)


@blueprint.post("/assessment/attempts/<int:attempt_id>/override")
@login_required
def override(attempt_id: int):  # type: ignore[no-untyped-def]
    """A tutor replaces one item's mark, with a reason."""
    return _review_action(attempt_id, lambda dbs, f: review.override_mark(
        dbs, current_user, attempt_id, f.get("item"), f.get("points"), f.get("reason"), f.get("comment"),
        server_now()), "Mark changed.")


@blueprint.post("/assessment/attempts/<int:attempt_id>/comment")
@login_required
def comment(attempt_id: int):  # type: ignore[no-untyped-def]
    """A tutor's comment on the attempt."""
    return _review_action(attempt_id, lambda dbs, f: review.add_comment(
        dbs, current_user, attempt_id, f.get("item"), f.get("comment"), server_now()), "Comment added.")


@blueprint.get("/courses/<int:course_id>/grades.csv")
@login_required
def grades_csv(course_id: int):  # type: ignore[no-untyped-def]
    """The grades export as a download."""
    dbs = get_session()
    try:
        text = review.grades_csv(dbs, current_user, course_id, server_now())
    except Refused as refused:
        _refused(refused)
    dbs.commit()
    return Response(text, mimetype="text/csv", headers={
        "Content-Disposition": f'attachment; filename="grades-{course_id}.csv"', "Cache-Control": "no-store"})


@blueprint.route("/courses/<int:course_id>/survey", methods=["GET", "POST"])
@login_required
def survey_page(course_id: int):  # type: ignore[no-untyped-def]
    """The system evaluation questionnaire (students of the course, once)."""
    dbs = get_session()
    try:
        course = bank.student_course(dbs, current_user, course_id)
    except Refused as refused:
        _refused(refused)
    errors: dict[str, str] = {}
    if request.method == "POST":
        try:
            ratings, comments = parse_survey(request.form.to_dict())
            survey.submit_survey(dbs, current_user, course_id, ratings, comments)
        except InvalidField as invalid:
            errors[invalid.field] = invalid.message
        except Refused as refused:
            errors["form"] = refused.message
        if not errors:
            dbs.commit()
            flash("Thank you: your answers were recorded.", "success")
            return redirect(url_for("assessment_pages.hub"), 303)
        dbs.rollback()
    answered = survey.has_answered(dbs, current_user.id, course_id)
    return render_template("assessment/survey.html", course=course, items=SURVEY_ITEMS, answers=AGREEMENT,
                           errors=errors, form=request.form, answered=answered, css=CSS), 400 if errors else 200


@blueprint.get("/courses/<int:course_id>/survey/results")
@login_required
def survey_results(course_id: int):  # type: ignore[no-untyped-def]
    """The distribution of answers per question as a chart (server-rendered SVG), and the comments."""
    dbs = get_session()
    try:
        items, comments = survey.results(dbs, current_user, course_id)
    except Refused as refused:
        _refused(refused)
    course = dbs.scalar(select(Course).where(Course.id == course_id))
    return render_template("assessment/survey_results.html", course=course, items=items, comments=comments,
                           answers=AGREEMENT, css=CSS)
