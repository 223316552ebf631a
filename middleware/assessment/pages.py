"""Assessment pages: the tutor's bank and tests, attempts and review; the student's tests, attempts, survey."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from datetime import UTC
from typing import Any

from flask import Blueprint, Response, abort, flash, redirect, render_template, request, url_for
from flask.typing import ResponseReturnValue
from flask_babel import gettext as _  # type: ignore[import-untyped]
from flask_login import current_user, login_required
from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.assessment import attempts, bank, recommendations, review, survey
from middleware.assessment.attempts import window_state
from middleware.assessment.recording import finish_recording, record_after_commit
from middleware.assessment.routes import controls_robot, own_robot, server_now
from middleware.assessment.schemas import (
    AGREEMENT,
    RUBRIC_ROWS,
    ExamInput,
    QuestionInput,
    form_choice_numbers,
    form_rubric,
    parse_exam,
    parse_question,
    parse_survey,
)
from middleware.assessment.survey_statements import parse_statements, parse_title, statements_text
from middleware.auth.schemas import InvalidField
from middleware.courses.services import list_courses
from middleware.db import get_session
from middleware.errors import Refused, flashed, unless_refused
from middleware.models import Course
from middleware.validation import decimal_int

blueprint = Blueprint("assessment_pages", __name__)
CSS = "pages/assessment/assessment.css"


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
def hub() -> ResponseReturnValue:
    """Students: their tests (open now, upcoming, done) and recommendations; tutors: the courses they assess."""
    dbs, now = get_session(), server_now()
    attempts.settle_due(dbs, now, user_id=current_user.id)
    courses = []
    for view in list_courses(dbs, current_user):
        entry: dict[str, Any] = {"course": view, "teaches": bank.may_teach(dbs, current_user, view.id)}
        if not entry["teaches"] and view.my_role == "student":
            groups: dict[str, list[Any]] = {"open": [], "upcoming": [], "done": []}
            for exam in bank.list_exams(dbs, view.id):
                mine = review.my_marked_attempts(dbs, current_user.id, exam.id)
                state = window_state(exam, now)
                used_up = exam.max_attempts is not None and len(mine) >= exam.max_attempts \
                    and all(a.status == "submitted" for a in mine)
                key = "done" if state == "closed" or used_up else state
                groups[key].append({"exam": exam, "attempts": mine})
            entry["groups"] = groups
            entry["topics"] = recommendations.topic_scores(dbs, current_user.id, view.id)
            entry["recommendations"] = recommendations.recommend(dbs, current_user.id, view.id, now)
            entry["answered_survey"] = survey.has_answered(dbs, current_user.id, view.id)
            entry["survey"] = survey.survey_of(dbs, view.id)
        courses.append(entry)
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
            "correct": ", ".join(str(i + 1) for i in correct) if isinstance(correct, list) else str((correct or 0) + 1)
            if "choices" in spec else "",
            "value": repr(spec["value"]) if "value" in spec else "",
            "tolerance": repr(spec["tolerance"]) if "tolerance" in spec else "",
            "unit": spec.get("unit", ""), "accepted": "\n".join(spec.get("accepted", [])),
            "case_sensitive": "1" if spec.get("case_sensitive") else "",
            "low_label": spec.get("low_label", ""), "high_label": spec.get("high_label", "")}


def _form_question(form: dict[str, Any]) -> QuestionInput:
    """A question from the bank editor, whose right choices are numbered from 1 (the API's from 0)."""
    if form.get("kind") in ("single", "multiple"):
        return parse_question({**form, "correct": form_choice_numbers(form.get("correct"), form.get("choices"))})
    return parse_question(form)


TASK_FIELDS = ("x_m", "y_m", "x1_m", "y1_m", "x2_m", "y2_m", "distance_m", "min_travel_m")


def _rubric_rows(bands: list[list[float]]) -> dict[str, str]:
    """The stored bands as the test editor's rows (share in percent)."""
    rows = {}
    for row, (bound, share) in enumerate(bands[:RUBRIC_ROWS]):
        rows[f"rubric_bound_{row}"], rows[f"rubric_share_{row}"] = f"{bound:g}", f"{share * 100:g}"
    return rows


def _form_exam(form: dict[str, Any]) -> ExamInput:
    """A test from the test editor, whose rubric comes as rows."""
    return parse_exam({**form, "rubric": form_rubric(form)})


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
                     **_rubric_rows(task.get("rubric") or [])})
        form.update({name: repr(task[name]) for name in TASK_FIELDS if name in task})
    return form


def _course_page(course_id: int, status: int = 200, errors: dict[str, str] | None = None,
                 form: dict[str, Any] | None = None, editing: tuple[str, int] | None = None,
                 error_key: str = ""):
    """The tutor's page; editing ("question" | "exam", id) opens that item's edit form (prefilled unless form)."""
    dbs, now = get_session(), server_now()
    course = bank.teaching_course(dbs, current_user, course_id)
    questions = bank.list_questions(dbs, current_user, course_id)
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
def course_page(course_id: int) -> ResponseReturnValue:
    """The tutor's bank editor, tests, grades export and survey results for a course; ?question=<id> or ?exam=<id>
    opens that question's or test's edit form."""
    for kind in ("question", "exam"):
        wanted = decimal_int(request.args.get(kind), 1)
        if wanted is not None:
            return _course_page(course_id, editing=(kind, wanted))
    return _course_page(course_id)


def _course_action(course_id: int, action: Callable[[Session, dict[str, Any]], object], success: str,
                   error_key: str, editing: tuple[str, int] | None = None,
                   keep_form: bool = True) -> ResponseReturnValue:
    """Runs a form's action; on a refusal, the page again with the message (and the form as sent, if keep_form;
    always for an invalid field)."""
    form: dict[str, Any] = request.form.to_dict()
    if error_key == "exam":
        form["question_ids"] = request.form.getlist("question_ids")

    def act() -> ResponseReturnValue:
        dbs = get_session()
        bank.teaching_course(dbs, current_user, course_id)
        action(dbs, form)
        flash(success, "success")
        return redirect(url_for("assessment_pages.course_page", course_id=course_id), 303)

    def page_again(refused: Refused) -> ResponseReturnValue:
        if isinstance(refused, InvalidField):
            return _course_page(course_id, 400, {error_key: f"{refused.field}: {refused.message}"}, form, editing,
                                error_key)
        return _course_page(course_id, refused.status, {error_key: refused.message}, form if keep_form else None,
                            editing, error_key)

    return unless_refused(act, page_again)


def _own_question(dbs: Any, course_id: int, question_id: int) -> Any:
    question = bank.course_question(dbs, current_user, question_id)
    if question.course_id != course_id:
        raise Refused(404, "unknown_question", _("There is no question with id %(question_id)s here.",
                                                       question_id=question_id), "question_id")
    return question


def _own_exam(dbs: Any, course_id: int, exam_id: int) -> Any:
    exam = bank.managed_exam(dbs, current_user, exam_id)
    if exam.course_id != course_id:
        raise Refused(404, "unknown_exam", _("There is no test with id %(exam_id)s here.", exam_id=exam_id), "exam_id")
    return exam


@blueprint.post("/courses/<int:course_id>/assessment/questions")
@login_required
def add_question(course_id: int) -> ResponseReturnValue:
    """Adds a question from the bank editor's form."""
    return _course_action(course_id, lambda dbs, form: bank.add_question(dbs, current_user, course_id,
                                                                         _form_question(form)),
                          _("Question added to the bank."), "question")


@blueprint.post("/courses/<int:course_id>/assessment/questions/<int:question_id>")
@login_required
def edit_question(course_id: int, question_id: int) -> ResponseReturnValue:
    """Replaces a question from its edit form (attempts already graded keep their marks)."""
    def action(dbs: Session, form: dict[str, Any]) -> None:
        _own_question(dbs, course_id, question_id)
        bank.update_question(dbs, current_user, question_id, _form_question(form))

    return _course_action(course_id, action, f"Question #{question_id} saved.", "question",
                          ("question", question_id))


@blueprint.post("/courses/<int:course_id>/assessment/questions/<int:question_id>/delete")
@login_required
def delete_question(course_id: int, question_id: int) -> ResponseReturnValue:
    """Removes a question from the bank (and from the tests nobody has attempted)."""
    def action(dbs: Session, _form: dict[str, Any]) -> None:
        _own_question(dbs, course_id, question_id)
        bank.delete_question(dbs, current_user, question_id)

    return _course_action(course_id, action, f"Question #{question_id} deleted.", "question",
                          ("question", question_id), keep_form=False)


@blueprint.post("/courses/<int:course_id>/assessment/bank")
@login_required
def import_bank(course_id: int) -> ResponseReturnValue:
    """Imports a bank file (JSON)."""
    def action(dbs: Session, _form: dict[str, Any]) -> None:
        upload = request.files.get("file")
        if upload is None or not upload.filename:
            raise InvalidField("file", _("Choose a question bank file (JSON) to import."))
        bank.import_bank(dbs, current_user, course_id, upload.read())

    return _course_action(course_id, action, _("Question bank imported."), "file")


@blueprint.post("/courses/<int:course_id>/assessment/exams")
@login_required
def create_exam(course_id: int) -> ResponseReturnValue:
    """Creates a quiz or a timed test from the test editor's form."""
    return _course_action(course_id, lambda dbs, form: bank.create_exam(dbs, current_user, course_id,
                                                                        _form_exam(form)), _("Test created."), "exam")


@blueprint.post("/courses/<int:course_id>/assessment/exams/<int:exam_id>")
@login_required
def edit_exam(course_id: int, exam_id: int) -> ResponseReturnValue:
    """Changes a test from its edit form (only its title and times once someone has started it)."""
    def action(dbs: Session, form: dict[str, Any]) -> None:
        exam = _own_exam(dbs, course_id, exam_id)
        data = _form_exam(form)
        if set(data.question_ids) == set(exam.question_ids or []):  # the checkboxes' order is the bank's
            data = replace(data, question_ids=list(exam.question_ids))
        bank.update_exam(dbs, current_user, exam_id, data)

    return _course_action(course_id, action, _("Test saved."), "exam", ("exam", exam_id))


@blueprint.post("/courses/<int:course_id>/assessment/exams/<int:exam_id>/delete")
@login_required
def delete_exam(course_id: int, exam_id: int) -> ResponseReturnValue:
    """Deletes a test nobody has attempted; a test with attempts is refused with the reason."""
    def action(dbs: Session, _form: dict[str, Any]) -> None:
        _own_exam(dbs, course_id, exam_id)
        bank.delete_exam(dbs, current_user, exam_id)

    return _course_action(course_id, action, _("Test deleted."), "exam", ("exam", exam_id), keep_form=False)


@blueprint.get("/assessment/exams/<int:exam_id>")
@login_required
def exam_page(exam_id: int) -> ResponseReturnValue:
    """A student's start page for an exam, or the tutor's list of attempts."""
    dbs, now = get_session(), server_now()
    exam = bank.get_exam(dbs, exam_id)
    teaches = bank.may_teach(dbs, current_user, exam.course_id)
    if not teaches:
        bank.student_course(dbs, current_user, exam.course_id)
    rows = review.list_attempts(dbs, current_user, exam_id, now) if teaches else None
    mine = None if teaches else review.my_marked_attempts(dbs, current_user.id, exam_id)
    return render_template("assessment/exam.html", exam=review.exam_dict(exam, now), rows=rows, mine=mine,
                           teaches=teaches, course=dbs.get(Course, exam.course_id), css=CSS)


@blueprint.post("/assessment/exams/<int:exam_id>/start")
@login_required
def start(exam_id: int) -> ResponseReturnValue:
    """Starts (or resumes) the student's attempt and opens it."""
    def begin() -> ResponseReturnValue:
        dbs = get_session()
        exam = bank.get_exam(dbs, exam_id)
        bank.student_course(dbs, current_user, exam.course_id)
        attempt = attempts.start_attempt(dbs, current_user, exam_id, server_now(), controls_robot, own_robot)
        record_after_commit(attempt, exam)
        return redirect(url_for("assessment_pages.attempt_page", attempt_id=attempt.id), 303)

    return unless_refused(begin, flashed(url_for("assessment_pages.exam_page", exam_id=exam_id)))



@blueprint.get("/assessment/attempts/<int:attempt_id>")
@login_required
def attempt_page(attempt_id: int) -> ResponseReturnValue:
    """Taking an attempt (its student), the corrected attempt, or the tutor's review."""
    dbs = get_session()
    view = review.attempt_view(dbs, current_user, attempt_id, server_now())
    exam = bank.get_exam(dbs, view["exam"]["id"])
    teaches = bank.may_teach(dbs, current_user, exam.course_id)
    owner = attempts.get_attempt(dbs, attempt_id).user_id == current_user.id
    return render_template("assessment/attempt.html", a=view, teaches=teaches, owner=owner, css=CSS,
                           questions={str(q["id"]): q for q in view["questions"]}), 200, {"Cache-Control": "no-store"}


@blueprint.post("/assessment/attempts/<int:attempt_id>/submit")
@login_required
def submit(attempt_id: int) -> ResponseReturnValue:
    """Submits the attempt with the form's answers (without JavaScript, too)."""
    back = url_for("assessment_pages.attempt_page", attempt_id=attempt_id)

    def hand_in() -> ResponseReturnValue:
        dbs = get_session()
        owner = attempts.get_attempt(dbs, attempt_id)
        trace = finish_recording(attempt_id) if owner.user_id == current_user.id else None
        attempts.submit_attempt(dbs, current_user, attempt_id, server_now(), _form_answers(), trace)
        flash(_("Submitted. Your corrected attempt is below."), "success")
        return redirect(back, 303)

    return unless_refused(hand_in, flashed(back))


def _review_action(attempt_id: int, action: Callable[[Session, Any], object], success: str) -> ResponseReturnValue:
    back = url_for("assessment_pages.attempt_page", attempt_id=attempt_id)

    def act() -> ResponseReturnValue:
        action(get_session(), request.form)
        flash(success, "success")
        return redirect(back, 303)

    return unless_refused(act, flashed(back))


@blueprint.post("/assessment/attempts/<int:attempt_id>/override")
@login_required
def override(attempt_id: int) -> ResponseReturnValue:
    """A tutor replaces one item's mark, with a reason."""
    return _review_action(attempt_id, lambda dbs, f: review.override_mark(
        dbs, current_user, attempt_id, f.get("item"), f.get("points"), f.get("reason"), f.get("comment"),
        server_now()), _("Mark changed."))


@blueprint.post("/assessment/attempts/<int:attempt_id>/comment")
@login_required
def comment(attempt_id: int) -> ResponseReturnValue:
    """A tutor's comment on the attempt."""
    return _review_action(attempt_id, lambda dbs, f: review.add_comment(
        dbs, current_user, attempt_id, f.get("item"), f.get("comment"), server_now()), _("Comment added."))


@blueprint.get("/courses/<int:course_id>/grades.csv")
@login_required
def grades_csv(course_id: int) -> ResponseReturnValue:
    """The grades export as a download."""
    text = review.grades_csv(get_session(), current_user, course_id, server_now())
    return Response(text, mimetype="text/csv", headers={
        "Content-Disposition": f'attachment; filename="grades-{course_id}.csv"', "Cache-Control": "no-store"})


@blueprint.get("/courses/<int:course_id>/grades")
@login_required
def gradebook(course_id: int) -> ResponseReturnValue:
    """The gradebook: every student against every test, with the CSV export beside it."""
    dbs = get_session()
    book = review.gradebook(dbs, current_user, course_id, server_now())
    course = bank.teaching_course(dbs, current_user, course_id)
    return render_template("assessment/gradebook.html", course=course, book=book, css=CSS)


@blueprint.route("/courses/<int:course_id>/survey", methods=["GET", "POST"])
@login_required
def survey_page(course_id: int) -> ResponseReturnValue:
    """The system evaluation questionnaire (students of the course, once)."""
    course = bank.student_course(get_session(), current_user, course_id)

    def page(errors: dict[str, str]) -> ResponseReturnValue:
        answered = survey.has_answered(get_session(), current_user.id, course_id)
        return render_template("assessment/survey.html", course=course, survey=survey.survey_of(get_session(),
                               course_id), answer_names=survey.answer_names, errors=errors, form=request.form,
                               answered=answered, css=CSS), 400 if errors else 200

    def answer() -> ResponseReturnValue:
        ratings, comments = parse_survey(request.form.to_dict(), survey.survey_of(get_session(), course_id).statements)
        survey.submit_survey(get_session(), current_user, course_id, ratings, comments)
        flash(_("Thank you: your answers were recorded."), "success")
        return redirect(url_for("assessment_pages.hub"), 303)

    if request.method != "POST":
        return page({})
    return unless_refused(answer, lambda refused: page(
        {refused.field if isinstance(refused, InvalidField) else "form": refused.message}))


@blueprint.route("/courses/<int:course_id>/survey/edit", methods=["GET", "POST"])
@login_required
def survey_editor(course_id: int) -> ResponseReturnValue:
    """The course's tutor writes its survey: a title and statements, one per line with what 1 and 5 mean."""
    dbs = get_session()
    course = bank.teaching_course(dbs, current_user, course_id)

    def page(errors: dict[str, str], form: dict[str, str] | None = None) -> ResponseReturnValue:
        current = survey.survey_of(dbs, course_id)
        shown = form or {"title": current.title, "statements": statements_text(current.statements)}
        return render_template("assessment/survey_edit.html", course=course, survey=current, form=shown,
                               errors=errors, answered=survey.respondent_count(dbs, course_id),
                               css=CSS), 400 if errors else 200

    def save() -> ResponseReturnValue:
        survey.write_survey(dbs, current_user, course_id, parse_title(request.form.get("title")),
                            parse_statements(request.form.get("statements", "")))
        flash(_("The survey is saved: students of the course now rate these statements."), "success")
        return redirect(url_for("assessment_pages.survey_editor", course_id=course_id), 303)

    if request.method != "POST":
        return page({})
    return unless_refused(save, lambda refused: page(
        {refused.field or "form": refused.message}, request.form.to_dict()))


@blueprint.get("/courses/<int:course_id>/survey/results")
@login_required
def survey_results(course_id: int) -> ResponseReturnValue:
    """The distribution of answers per question as a chart (server-rendered SVG), and the comments."""
    dbs = get_session()
    results = survey.results(dbs, current_user, course_id)
    course = dbs.scalar(select(Course).where(Course.id == course_id))
    return render_template("assessment/survey_results.html", course=course, results=results, items=results.items,
                           comments=results.comments, min_respondents=survey.MIN_RESPONDENTS,
                           answers=_answer_columns(results.items), css=CSS)


def _answer_columns(items: list[survey.ItemDistribution]) -> tuple[str, ...]:
    """The results table's columns: the agreement scale's names when every statement uses it, else 1 to 5."""
    if all(survey.answer_names(i.low_label, i.high_label) == AGREEMENT for i in items):
        return AGREEMENT
    return ("1", "2", "3", "4", "5")
