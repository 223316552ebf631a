"""Assessment pages: the tutor's bank and tests, attempts and review; the student's tests, attempts, survey."""

from __future__ import annotations

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


def _course_page(course_id: int, status: int = 200, errors: dict[str, str] | None = None,
                 form: dict[str, str] | None = None):  # type: ignore[no-untyped-def]
    dbs, now = get_session(), server_now()
    try:
        course = bank.teaching_course(dbs, current_user, course_id)
        questions = bank.list_questions(dbs, current_user, course_id)
    except Refused as refused:
        _refused(refused)
    exams = [review.exam_dict(e, now) for e in bank.list_exams(dbs, course_id)]
    return render_template("assessment/course.html", course=course, questions=questions, exams=exams,
                           errors=errors or {}, form=form or {}, css=CSS), status


@blueprint.get("/courses/<int:course_id>/assessment")
@login_required
def course_page(course_id: int):  # type: ignore[no-untyped-def]
    """The tutor's bank editor, tests, grades export and survey results for a course."""
    return _course_page(course_id)


def _course_action(course_id: int, action, success: str, error_key: str):  # type: ignore[no-untyped-def]
    dbs, form = get_session(), request.form.to_dict()
    try:
        bank.teaching_course(dbs, current_user, course_id)
        action(dbs, form)
    except Refused as refused:
        if refused.status in (403, 404):
            _refused(refused)
        dbs.rollback()
        return _course_page(course_id, refused.status, {error_key: refused.message}, form)
    except InvalidField as invalid:
        dbs.rollback()
        return _course_page(course_id, 400, {error_key: f"{invalid.field}: {invalid.message}"}, form)
    dbs.commit()
    flash(success, "success")
    return redirect(url_for("assessment_pages.course_page", course_id=course_id), 303)


@blueprint.post("/courses/<int:course_id>/assessment/questions")
@login_required
def add_question(course_id: int):  # type: ignore[no-untyped-def]
    """Adds a question from the bank editor's form."""
    return _course_action(course_id, lambda dbs, form: bank.add_question(dbs, current_user, course_id,
                                                                         parse_question(form)),
                          "Question added to the bank.", "question")


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
    def action(dbs, form):  # type: ignore[no-untyped-def]
        data = dict(form)
        data["question_ids"] = request.form.getlist("question_ids")
        bank.create_exam(dbs, current_user, course_id, parse_exam(data))

    return _course_action(course_id, action, "Test created.", "exam")


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
