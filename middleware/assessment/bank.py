"""The question bank of a course and the exams built from it (tutors of the course, admins). The caller commits."""

from __future__ import annotations

import json
from dataclasses import replace
from typing import Any

from flask_babel import gettext  # type: ignore[import-untyped]
from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.assessment.obstacle_zone import with_scene_truth
from middleware.assessment.policy import get_exam, may_teach, student_course, teaching_course  # noqa: F401
from middleware.assessment.schemas import BANK_FORMAT, ExamInput, QuestionInput, parse_bank_file
from middleware.auth.schemas import InvalidField
from middleware.errors import Refused
from middleware.models import User
from middleware.models.assessment import Attempt, Exam, Question
from middleware.validation import printable


def question_dict(question: Question, with_key: bool = True) -> dict[str, Any]:
    """A question as JSON; without the key (correct choices, value, accepted answers) for students."""
    spec = dict(question.spec)
    if not with_key:
        spec = {"choices": spec["choices"]} if "choices" in spec else (
            {"unit": spec.get("unit", "")} if question.kind == "numeric" else
            spec if question.kind == "rating" else {})  # a rating's ends are no key
    return {"id": question.id, "kind": question.kind, "prompt": question.prompt, "topics": list(question.topics),
            "points": question.points, **spec}


def list_questions(session: Session, actor: User, course_id: int) -> list[Question]:
    """The course's bank, oldest first."""
    teaching_course(session, actor, course_id)
    return list(session.scalars(select(Question).where(Question.course_id == course_id).order_by(Question.id)))


def add_question(session: Session, actor: User, course_id: int, data: QuestionInput) -> Question:
    """Adds a question to the course's bank."""
    teaching_course(session, actor, course_id)
    question = Question(course_id=course_id, kind=data.kind, prompt=data.prompt, topics=data.topics, spec=data.spec,
                        points=data.points)
    session.add(question)
    session.flush()
    return question


def course_question(session: Session, actor: User, question_id: int) -> Question:
    """A question of a course the actor teaches."""
    question = session.get(Question, question_id)
    if question is None:
        raise Refused(404, "unknown_question", gettext("There is no question with id %(question_id)s.",
                                                       question_id=question_id), "question_id")
    teaching_course(session, actor, question.course_id)
    return question


def update_question(session: Session, actor: User, question_id: int, data: QuestionInput) -> Question:
    """Replaces a question (attempts already graded keep their marks: results are stored with them)."""
    question = course_question(session, actor, question_id)
    question.kind, question.prompt, question.topics = data.kind, data.prompt, data.topics
    question.spec, question.points = data.spec, data.points
    return question


def delete_question(session: Session, actor: User, question_id: int) -> None:
    """Removes a question from the bank and from the course's exams that have no attempt yet (exams already
    attempted keep the id: their attempts' results are stored, and questions_of skips it)."""
    question = course_question(session, actor, question_id)
    for exam in list_exams(session, question.course_id):
        if question.id in (exam.question_ids or []) and not has_attempts(session, exam.id):
            exam.question_ids = [i for i in exam.question_ids if i != question.id]
    session.delete(question)
    session.flush()


def has_attempts(session: Session, exam_id: int) -> bool:
    """True once anyone has started the exam."""
    return session.scalar(select(Attempt.id).where(Attempt.exam_id == exam_id).limit(1)) is not None


def export_bank(session: Session, actor: User, course_id: int) -> str:
    """The course's bank as a JSON file that import_bank reads back."""
    questions = list_questions(session, actor, course_id)
    items = []
    for question in questions:
        item = question_dict(question)
        item.pop("id")
        items.append(item)
    # printable: a lone surrogate stored before the edge refused them would make the file unencodable.
    return printable(json.dumps({"format": BANK_FORMAT, "questions": items}, indent=2, ensure_ascii=False))


def import_bank(session: Session, actor: User, course_id: int, data: bytes) -> list[Question]:
    """Adds every question of a bank file, or none when any is invalid (the error lists each problem)."""
    teaching_course(session, actor, course_id)
    return [add_question(session, actor, course_id, item) for item in parse_bank_file(data)]


def _check_questions(session: Session, course_id: int, ids: list[int]) -> None:
    found = set(session.scalars(select(Question.id).where(Question.course_id == course_id, Question.id.in_(ids))))
    missing = [i for i in ids if i not in found]
    if missing:
        raise InvalidField("question_ids", gettext("Questions %(value)s are not in this course's bank.",
                                                   value=', '.join(map(str, missing))))


def create_exam(session: Session, actor: User, course_id: int, data: ExamInput) -> Exam:
    """A new quiz or timed test of the course."""
    teaching_course(session, actor, course_id)
    _check_questions(session, course_id, data.question_ids)
    exam = Exam(course_id=course_id, title=data.title, kind=data.kind, opens_at=data.opens_at,
                closes_at=data.closes_at, duration_s=data.duration_s, max_attempts=data.max_attempts,
                question_ids=data.question_ids, task=with_scene_truth(data.task, data.robot_name),
                robot_name=data.robot_name)
    session.add(exam)
    session.flush()
    return exam


def managed_exam(session: Session, actor: User, exam_id: int) -> Exam:
    """An exam of a course the actor teaches."""
    exam = get_exam(session, exam_id)
    teaching_course(session, actor, exam.course_id)
    return exam


def update_exam(session: Session, actor: User, exam_id: int, data: ExamInput) -> Exam:
    """Changes an exam; its questions and task are frozen once someone has started it."""
    exam = managed_exam(session, actor, exam_id)
    _check_questions(session, exam.course_id, data.question_ids)
    data = replace(data, task=with_scene_truth(data.task, data.robot_name))
    started = has_attempts(session, exam.id)
    if started and (data.question_ids != exam.question_ids or data.task != exam.task or data.kind != exam.kind):
        raise Refused(409, "exam_started", gettext("Students have started this test: only its title and times can "
                                                   "change."),
                      "question_ids")
    exam.title, exam.kind, exam.opens_at, exam.closes_at = data.title, data.kind, data.opens_at, data.closes_at
    exam.duration_s, exam.max_attempts, exam.question_ids = data.duration_s, data.max_attempts, data.question_ids
    exam.task, exam.robot_name = data.task, data.robot_name
    return exam


def delete_exam(session: Session, actor: User, exam_id: int) -> None:
    """Deletes a test nobody has attempted; one with attempts is kept (its marks are grades)."""
    exam = managed_exam(session, actor, exam_id)
    if has_attempts(session, exam.id):
        raise Refused(409, "exam_has_attempts", gettext("“%(title)s” has attempts, so it cannot be deleted: their "
                                                        "marks are grades. Change its closing time to close it "
                                                        "instead.", title=exam.title), "exam_id")
    session.delete(exam)
    session.flush()


def list_exams(session: Session, course_id: int) -> list[Exam]:
    """The course's exams by opening time."""
    return list(session.scalars(select(Exam).where(Exam.course_id == course_id).order_by(Exam.id)))


def questions_of(session: Session, exam: Exam) -> list[Question]:
    """The exam's questions in its order (questions deleted from the bank since are skipped)."""
    by_id = {q.id: q for q in session.scalars(select(Question).where(Question.id.in_(exam.question_ids or [])))}
    return [by_id[i] for i in exam.question_ids or [] if i in by_id]
