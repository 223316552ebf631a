"""Assessment JSON API: bank, exams, attempts, the corrector, grades, recommendations, survey. Routes stay thin."""

from __future__ import annotations

from collections.abc import Callable
from datetime import UTC, datetime
from typing import Any

from flask import Blueprint, Response, current_app, jsonify, request
from flask.typing import ResponseReturnValue
from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import current_user, login_required
from sqlalchemy.orm import Session

from middleware.access.coordinator import access_coordinator
from middleware.api.contract import (
    BOOLEAN,
    ID,
    OBJECT,
    STRING,
    about,
    array,
    described,
    file_answer,
    number,
    obj,
    one_of,
    whole,
)
from middleware.assessment import attempts, bank, recommendations, review, survey
from middleware.assessment.recording import finish_recording, record_after_commit, robot_run
from middleware.assessment.schemas import BANK_FORMAT, parse_exam, parse_question, parse_survey
from middleware.assessment.survey_statements import parse_statements, parse_title
from middleware.db import get_session
from middleware.errors import ApiError
from middleware.models.assessment import Exam
from middleware.robots.link import RobotUnavailable
from middleware.robots.registry import robot_registry
from middleware.teaching.class_sessions import class_robot
from middleware.web import json_body

blueprint = Blueprint("assessment", __name__)


def server_now() -> datetime:
    """The server's clock (tests may set ASSESSMENT_CLOCK); the browser's clock is never used."""
    clock = current_app.config.get("ASSESSMENT_CLOCK")
    return clock() if clock else datetime.now(UTC)


def controls_robot(robot_name: str, user_id: int) -> bool:
    """True when the user controls the robot now (their turn, or their booking's priority gave it to them)."""
    try:
        return access_coordinator().controller_token(robot_name, user_id) is not None
    except Exception:  # an unknown robot: nobody controls it
        return False


def own_robot(exam: Exam, user_id: int) -> str | None:
    """The student's own robot in an open class session of the exam's course, when it runs the scene of the
    exam's robot (or that robot does not answer to say): the experimental attempt then runs there."""
    record = class_robot(get_session(), exam.course_id, user_id)
    if record is None:
        return None
    link = robot_registry().get(exam.robot_name or "")
    try:
        scene = link.info(max_age_s=5.0).scene_name if link is not None else None
    except RobotUnavailable:
        scene = None
    return record.name if scene in (None, record.scene) else None


def run(action: Callable[[Session], Any], status: int = 200) -> tuple[Response, int]:
    """Runs action in the request's unit of work and answers its result as JSON (a refusal is the error
    handler's; a TimeUp keeps the attempt submitted as it stood at the deadline)."""
    return jsonify(action(get_session())), status


# --- bank -----------------------------------------------------------------------------------------


@blueprint.get("/api/courses/<int:course_id>/questions")
@login_required
@described(answers={200: obj(("questions",), questions=array(OBJECT))})
def api_questions(course_id: int) -> ResponseReturnValue:
    """The course's question bank, with keys (its tutors, admins)."""
    return run(lambda dbs: {"questions": [bank.question_dict(q) for q in
                                          bank.list_questions(dbs, current_user, course_id)]})


@blueprint.post("/api/courses/<int:course_id>/questions")
@login_required
@described(
    body=obj(
        ("kind", "prompt"),
        kind=about("the question's kind"),
        prompt=about("the question"),
        topics=about("its topics"),
        points=about("its points"),
    ),
    answers={201: obj(("question",), question=OBJECT)},
)
def api_add_question(course_id: int) -> ResponseReturnValue:
    """{kind, prompt, topics, points, ...kind's fields}: adds a question."""
    data = json_body()

    def action(dbs: Session) -> dict[str, Any]:
        bank.teaching_course(dbs, current_user, course_id)
        return {"question": bank.question_dict(bank.add_question(dbs, current_user, course_id, parse_question(data)))}

    return run(action, 201)


@blueprint.put("/api/questions/<int:question_id>")
@login_required
@described(
    body=obj(("kind", "prompt"), kind=about("the question's kind"), prompt=about("the question")),
    answers={200: obj(("question",), question=OBJECT)},
    refusals=(409,),
)
def api_update_question(question_id: int) -> ResponseReturnValue:
    """Replaces a question."""
    data = json_body()

    def action(dbs: Session) -> dict[str, Any]:
        bank.course_question(dbs, current_user, question_id)
        return {"question": bank.question_dict(bank.update_question(dbs, current_user, question_id,
                                                                    parse_question(data)))}

    return run(action)


@blueprint.delete("/api/questions/<int:question_id>")
@login_required
@described(answers={200: obj(("deleted",), deleted=ID)}, refusals=(409,))
def api_delete_question(question_id: int) -> ResponseReturnValue:
    """Removes a question from the bank."""
    def action(dbs: Session) -> dict[str, int]:
        bank.delete_question(dbs, current_user, question_id)
        return {"deleted": question_id}

    return run(action)


@blueprint.get("/api/courses/<int:course_id>/bank.json")
@login_required
@described(answers={200: file_answer("application/json", "the bank as a file", schema=obj(
    ("format", "questions"), format=one_of(BANK_FORMAT),
    questions=array(obj(("kind", "prompt", "topics", "points"), description="a question and its kind's fields",
                        kind=STRING, prompt=STRING, topics=array(STRING), points=number()))))})
def api_export_bank(course_id: int) -> ResponseReturnValue:
    """The bank as a file to download."""
    text = bank.export_bank(get_session(), current_user, course_id)
    return Response(text, mimetype="application/json",
                    headers={"Content-Disposition": f'attachment; filename="question-bank-{course_id}.json"'})


@blueprint.post("/api/courses/<int:course_id>/bank")
@login_required
@described(
    form=obj(
        ("file",), file={"type": "string", "format": "binary", "description": "a bank file (the JSON body also works)"}
    ),
    answers={201: obj(("imported",), imported=whole(0))},
    refusals=(413,),
)
def api_import_bank(course_id: int) -> ResponseReturnValue:
    """A bank file (the upload 'file', or the JSON body): every question is added, or none."""
    def action(dbs: Session) -> dict[str, Any]:
        bank.teaching_course(dbs, current_user, course_id)
        upload = request.files.get("file")
        data = upload.read() if upload is not None else request.get_data()
        return {"imported": len(bank.import_bank(dbs, current_user, course_id, data))}

    return run(action, 201)


# --- exams ----------------------------------------------------------------------------------------


@blueprint.get("/api/courses/<int:course_id>/exams")
@login_required
@described(answers={200: obj(("exams",), exams=array(OBJECT))})
def api_exams(course_id: int) -> ResponseReturnValue:
    """The course's quizzes and tests (its students and tutors, admins)."""
    def action(dbs: Session) -> dict[str, Any]:
        if not bank.may_teach(dbs, current_user, course_id):
            bank.student_course(dbs, current_user, course_id)
        now = server_now()
        return {"exams": [review.exam_dict(e, now) for e in bank.list_exams(dbs, course_id)]}

    return run(action)


@blueprint.post("/api/courses/<int:course_id>/exams")
@login_required
@described(
    body=obj(
        ("title", "kind"),
        title=about("the test's title"),
        kind=about("quiz or test, or a task's kind"),
        opens_at=about("ISO 8601"),
        closes_at=about("ISO 8601"),
        duration_s=about("seconds"),
        max_attempts=about("attempts allowed"),
        question_ids=about("the questions' ids"),
    ),
    answers={201: obj(("exam",), exam=OBJECT)},
    refusals=(409,),
)
def api_create_exam(course_id: int) -> ResponseReturnValue:
    """{title, kind, opens_at, closes_at, duration_s, max_attempts, question_ids, task fields}: a new exam."""
    data = json_body()

    def action(dbs: Session) -> dict[str, Any]:
        bank.teaching_course(dbs, current_user, course_id)
        exam = bank.create_exam(dbs, current_user, course_id, parse_exam(data))
        return {"exam": review.exam_dict(exam, server_now())}

    return run(action, 201)


@blueprint.put("/api/exams/<int:exam_id>")
@login_required
@described(
    body=obj(title=about("the test's title"), kind=about("its kind")),
    answers={200: obj(("exam",), exam=OBJECT)},
    refusals=(409,),
)
def api_update_exam(exam_id: int) -> ResponseReturnValue:
    """Changes an exam (questions and task frozen once started)."""
    data = json_body()

    def action(dbs: Session) -> dict[str, Any]:
        bank.managed_exam(dbs, current_user, exam_id)
        return {"exam": review.exam_dict(bank.update_exam(dbs, current_user, exam_id, parse_exam(data)),
                                         server_now())}

    return run(action)


@blueprint.delete("/api/exams/<int:exam_id>")
@login_required
@described(answers={200: obj(("deleted",), deleted=ID)}, refusals=(409,))
def api_delete_exam(exam_id: int) -> ResponseReturnValue:
    """Deletes a test nobody has attempted (409 exam_has_attempts otherwise)."""
    def action(dbs: Session) -> dict[str, int]:
        bank.delete_exam(dbs, current_user, exam_id)
        return {"deleted": exam_id}

    return run(action)


# --- attempts -------------------------------------------------------------------------------------


@blueprint.get("/api/exams/<int:exam_id>/attempts")
@login_required
@described(answers={200: obj(("attempts",), attempts=array(OBJECT))})
def api_exam_attempts(exam_id: int) -> ResponseReturnValue:
    """Every attempt at the exam (its course's tutors, admins)."""
    return run(lambda dbs: {"attempts": review.list_attempts(dbs, current_user, exam_id, server_now())})


def start_attempt(dbs: Session, exam_id: int) -> Any:
    """Starts (or resumes) the student's attempt; starts recording for an experimental test."""
    attempt = attempts.start_attempt(dbs, current_user, exam_id, server_now(), controls_robot, own_robot)
    record_after_commit(attempt, bank.get_exam(dbs, exam_id))
    return attempt


@blueprint.post("/api/exams/<int:exam_id>/attempts")
@login_required
@described(answers={200: obj(("attempt",), attempt=OBJECT), 201: obj(("attempt",), attempt=OBJECT)}, refusals=(409,))
def api_start_attempt(exam_id: int) -> ResponseReturnValue:
    """Starts the student's attempt (or returns the one in progress)."""
    return run(lambda dbs: {"attempt": review.attempt_view(dbs, current_user, start_attempt(dbs, exam_id).id,
                                                           server_now())}, 201)


@blueprint.get("/api/attempts/<int:attempt_id>")
@login_required
@described(answers={200: obj(("attempt",), attempt=OBJECT)})
def api_attempt(attempt_id: int) -> ResponseReturnValue:
    """The attempt: questions, answers, time left by the server's clock; marks and comments once submitted."""
    return run(lambda dbs: {"attempt": review.attempt_view(dbs, current_user, attempt_id, server_now())})


@blueprint.patch("/api/attempts/<int:attempt_id>/answers")
@login_required
@described(
    body=obj(("answers",), answers=obj(description="item -> answer")),
    answers={200: obj(("saved", "answers"), saved=array(STRING), answers=OBJECT)},
    refusals=(409,),
)
def api_save_answers(attempt_id: int) -> ResponseReturnValue:
    """{answers: {item: answer}}: saves answers as the student goes (refused after the deadline)."""
    data = json_body()
    answers = data.get("answers")
    if not isinstance(answers, dict):
        raise ApiError(400, "invalid_field", gettext("answers must be an object of item -> answer."), "answers")

    def action(dbs: Session) -> dict[str, Any]:
        attempt = attempts.save_answers(dbs, current_user, attempt_id, answers, server_now())
        return {"saved": sorted(answers), "answers": attempt.answers}

    return run(action)


@blueprint.record_once
def _grade_settled_attempts_on_the_robot_s_run(_state: object) -> None:
    attempts.read_runs_from(robot_run)


@blueprint.post("/api/attempts/<int:attempt_id>/submit")
@login_required
@described(
    body=obj(answers=obj(description="item -> answer, saved before submitting")),
    body_required=False,
    answers={200: obj(("attempt",), attempt=OBJECT)},
    refusals=(409,),
)
def api_submit(attempt_id: int) -> ResponseReturnValue:
    """{answers?}: submits the attempt; it is graded at once (quizzes show the correction immediately)."""
    data = request.get_json(silent=True) or {}
    answers = data.get("answers") if isinstance(data, dict) and isinstance(data.get("answers"), dict) else None

    def action(dbs: Session) -> dict[str, Any]:
        owner = attempts.get_attempt(dbs, attempt_id)
        trace = finish_recording(attempt_id) if owner.user_id == current_user.id else None
        attempts.submit_attempt(dbs, current_user, attempt_id, server_now(), answers, trace)
        return {"attempt": review.attempt_view(dbs, current_user, attempt_id, server_now())}

    return run(action)


@blueprint.post("/api/attempts/<int:attempt_id>/overrides")
@login_required
@described(
    body=obj(
        ("item", "points", "reason"),
        item=about("the item"),
        points=about("the new mark"),
        reason=about("why"),
        comment=about("for the student"),
    ),
    answers={201: obj(("review_id",), review_id=ID)},
    refusals=(409,),
)
def api_override(attempt_id: int) -> ResponseReturnValue:
    """{item, points, reason, comment?}: a tutor replaces one item's mark."""
    data = json_body()
    return run(lambda dbs: {"review_id": review.override_mark(
        dbs, current_user, attempt_id, data.get("item"), data.get("points"), data.get("reason"),
        data.get("comment"), server_now()).id}, 201)


@blueprint.post("/api/attempts/<int:attempt_id>/comments")
@login_required
@described(
    body=obj(("comment",), comment=about("the comment's text"), item=about("the item it is about, or none")),
    answers={201: obj(("review_id",), review_id=ID)},
    refusals=(409,),
)
def api_comment(attempt_id: int) -> ResponseReturnValue:
    """{comment, item?}: a tutor's comment the student sees with the corrected attempt."""
    data = json_body()
    return run(lambda dbs: {"review_id": review.add_comment(dbs, current_user, attempt_id, data.get("item"),
                                                            data.get("comment"), server_now()).id}, 201)


# --- grades, recommendations, survey -------------------------------------------------------------


@blueprint.get("/api/courses/<int:course_id>/grades.csv")
@login_required
@described(answers={200: file_answer("text/csv", "best final mark per student and exam")})
def api_grades_csv(course_id: int) -> ResponseReturnValue:
    """Best final mark per student and exam, as CSV (its tutors, admins)."""
    text = review.grades_csv(get_session(), current_user, course_id, server_now())
    return Response(text, mimetype="text/csv", headers={
        "Content-Disposition": f'attachment; filename="grades-{course_id}.csv"', "Cache-Control": "no-store"})


@blueprint.get("/api/courses/<int:course_id>/recommendations")
@login_required
@described(answers={200: obj(("topics",), topics=array(OBJECT))})
def api_recommendations(course_id: int) -> ResponseReturnValue:
    """The student's per-topic results and the activities recommended for weak topics."""
    def action(dbs: Session) -> dict[str, Any]:
        bank.student_course(dbs, current_user, course_id)
        scores = recommendations.topic_scores(dbs, current_user.id, course_id)
        return {"topics": [{"topic": s.topic, "points": s.points, "max_points": s.max_points,
                            "ratio": round(s.ratio, 4)} for s in scores],
                "recommendations": [r.__dict__ for r in recommendations.recommend(dbs, current_user.id, course_id,
                                                                                   server_now())]}

    return run(action)


@blueprint.post("/api/courses/<int:course_id>/survey")
@login_required
@described(
    body={**obj(comments=about("free text")),
          "patternProperties": {"^s[0-9]+$": about("each statement's key (s1, s2, ...) -> its rating, 1 to 5")}},
    answers={201: obj(("answered",), answered=BOOLEAN)},
    refusals=(409,),
)
def api_survey(course_id: int) -> ResponseReturnValue:
    """{ratings: {item: 1-5}, comments}: the student's evaluation of the system, once."""
    data = json_body()

    def action(dbs: Session) -> dict[str, Any]:
        bank.student_course(dbs, current_user, course_id)
        ratings, comments = parse_survey(data, survey.survey_of(dbs, course_id).statements)
        survey.submit_survey(dbs, current_user, course_id, ratings, comments)
        return {"answered": True}

    return run(action, 201)


@blueprint.get("/api/courses/<int:course_id>/survey/results")
@login_required
@described(answers={200: obj(("respondents", "min_respondents"), respondents=whole(0), min_respondents=whole(0))})
def api_survey_results(course_id: int) -> ResponseReturnValue:
    """The distribution of answers per question and the comments (its tutors, admins); empty, with `hidden`,
    until MIN_RESPONDENTS have answered."""
    def action(dbs: Session) -> dict[str, Any]:
        answers = survey.results(dbs, current_user, course_id)
        return {"respondents": answers.respondents, "min_respondents": survey.MIN_RESPONDENTS,
                "hidden": answers.hidden, "questions": [i.to_dict() for i in answers.items],
                "comments": answers.comments}

    return run(action)


# A course's survey (_survey_dict): its title, whether its tutor wrote it, and its statements.
SURVEY = obj(("title", "written", "statements"), title=STRING, written=BOOLEAN,
             statements=array(obj(("key", "text", "low_label", "high_label"), key=STRING, text=STRING,
                                  low_label=STRING, high_label=STRING)))


def _survey_dict(form: survey.CourseSurveyForm) -> dict[str, Any]:
    return {"title": form.title, "written": form.written, "statements": [s.to_dict() for s in form.statements]}


@blueprint.get("/api/courses/<int:course_id>/survey/statements")
@login_required
@described(answers={200: SURVEY})
def api_survey_statements(course_id: int) -> ResponseReturnValue:
    """The course's survey as its students rate it (students and tutors of the course, admins)."""
    def action(dbs: Session) -> dict[str, Any]:
        if not bank.may_teach(dbs, current_user, course_id):
            bank.student_course(dbs, current_user, course_id)
        return _survey_dict(survey.survey_of(dbs, course_id))

    return run(action)


@blueprint.put("/api/courses/<int:course_id>/survey/statements")
@login_required
@described(
    body=obj(
        ("statements",),
        title=about("the survey's title (a default when none)"),
        statements=about("[{text, low_label, high_label}], or a line each: text | what 1 means | what 5 means"),
    ),
    answers={200: SURVEY},
    refusals=(409,),
)
def api_write_survey(course_id: int) -> ResponseReturnValue:
    """{title, statements: [{text, low_label, high_label}]}: the course's tutor writes its survey (409
    survey_answered once a student has answered)."""
    data = json_body()

    def action(dbs: Session) -> dict[str, Any]:
        return _survey_dict(survey.write_survey(dbs, current_user, course_id, parse_title(data.get("title")),
                                                parse_statements(data.get("statements"))))

    return run(action)
