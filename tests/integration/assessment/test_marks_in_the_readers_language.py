"""A mark with a fraction, over HTTP on the live app: a Spanish tutor overrides a mark typing it as Spanish writes it
(0,5), and the attempt, test and gradebook pages write every mark with the reader's decimal sign (0,5 in Spanish,
0.5 in English as before)."""

from __future__ import annotations

import html
import re
from datetime import UTC, datetime, timedelta

from tests.integration.bookings.conftest import api, client_as, course_people

__all__ = ["client_as", "course_people"]

SPANISH = {"Accept-Language": "es-ES,es;q=0.9"}
ENGLISH = {"Accept-Language": "en-GB,en;q=0.9"}


def _text(page: str) -> str:
    """What a person reads of the page's main part (tags dropped, spaces folded)."""
    main = page[page.index("<main"):] if "<main" in page else page
    return re.sub(r"\s+", " ", html.unescape(re.sub(r"<[^>]+>", " ", main)))


def test_a_spanish_tutor_types_a_mark_with_a_comma_and_everyone_reads_it_in_their_language(client_as,
                                                                                          course_people) -> None:
    tutor, student = client_as("tutor1"), client_as("student1")
    course_id = course_people["course"]
    status, body = api(tutor, "POST", f"/api/courses/{course_id}/questions",
                       {"kind": "numeric", "prompt": "Laser range?", "value": 8, "tolerance": 0.5, "unit": "m",
                        "points": 2})
    assert status == 201, body
    question_id = body["question"]["id"]
    now = datetime.now(UTC)
    status, body = api(tutor, "POST", f"/api/courses/{course_id}/exams", {
        "title": "Sensors", "kind": "theory", "opens_at": (now - timedelta(minutes=1)).isoformat(),
        "closes_at": (now + timedelta(hours=1)).isoformat(), "duration_s": 600, "question_ids": [question_id]})
    assert status == 201, body
    exam_id = body["exam"]["id"]
    status, body = api(student, "POST", f"/api/exams/{exam_id}/attempts", {})
    assert status == 201, body
    attempt_id = body["attempt"]["id"]
    status, body = api(student, "POST", f"/api/attempts/{attempt_id}/submit", {"answers": {str(question_id): "3"}})
    assert status == 200 and body["attempt"]["score"] == 0, body

    page = f"/assessment/attempts/{attempt_id}"
    status, headers, _ = tutor.request("POST", f"{page}/override", {
        "csrf_token": tutor.csrf_token(page), "item": str(question_id), "points": "0,5",
        "reason": "La unidad faltaba"}, headers=SPANISH)
    assert status == 303, headers
    shown = tutor.request("GET", page, headers=SPANISH)[2]
    assert 'class="flash flash--success">Nota cambiada.<' in shown, _text(shown)[:600]
    said = _text(shown)
    assert "0,5/2 puesto por el tutor: La unidad faltaba" in said and "Nota: 0,5 / 2" in said, said[:1500]
    assert "Sustituye a la nota automática 0: Fuera del intervalo aceptado (8 ± 0,5 m)." in said, said[:1500]
    assert "0.5" not in said

    for reader in (student, tutor):
        spanish = _text(reader.request("GET", page, headers=SPANISH)[2])
        english = _text(reader.request("GET", page, headers=ENGLISH)[2])
        assert "nota puesta en 0,5 (La unidad faltaba)." in spanish and "0.5" not in spanish, spanish[:1500]
        assert "mark set to 0.5 (La unidad faltaba)." in english and "0,5" not in english, english[:1500]
    assert "0,5/2" in _text(student.request("GET", f"/assessment/exams/{exam_id}", headers=SPANISH)[2])
    book = _text(tutor.request("GET", f"/courses/{course_id}/grades", headers=SPANISH)[2])
    assert " 0,5 " in book and "0.5" not in book, book[:1500]
    assert " 0.5 " in _text(tutor.request("GET", f"/courses/{course_id}/grades", headers=ENGLISH)[2])

    # A mark outside the item's points is still refused, as before.
    status, _, _ = tutor.request("POST", f"{page}/override", {
        "csrf_token": tutor.csrf_token(page), "item": str(question_id), "points": "2,5", "reason": "x"},
        headers=SPANISH)
    assert status == 303
    refused = tutor.request("GET", page, headers=SPANISH)[2]
    assert 'class="flash flash--error">points debe estar entre 0 y 2.<' in refused, _text(refused)[:600]
    assert "Nota: 0,5 / 2" in _text(refused)


def _task_feedbacks() -> list[str]:
    """The experimental task grader's own sentences, one of each kind, as it stores them (in English)."""
    from middleware.assessment import trace_grading

    trace = [[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], [5.0, 1.43, 0.52, 0.0, 1.4, 0.5, 0.0]]
    wall = {"kind": "wall_following", "x1_m": -5.0, "y1_m": 1.0, "x2_m": 5.0, "y2_m": 1.0, "distance_m": 0.4,
            "min_travel_m": 1.0}
    zone = {"kind": "obstacle_zone", "bounds": [0.0, 0.0, 2.0, 2.0],
            "obstacles": [{"center_x_m": 0.5, "center_y_m": 0.5, "half_x_m": 0.25, "half_y_m": 0.25, "yaw_rad": 0.0}]}
    return [trace_grading.measure(task, trace if use_trace else [], report).feedback for task, use_trace, report in (
        ({"kind": "reach_point", "x_m": 1.5, "y_m": 0.5}, True, None),
        (wall, True, None),
        ({**wall, "min_travel_m": 3.0}, True, None),
        ({"kind": "report_pose"}, True, {"x_m": "1.2", "y_m": "0.4", "t_s": "5"}),
        ({"kind": "report_pose"}, True, None),
        ({"kind": "reach_point", "x_m": 1.5, "y_m": 0.5}, False, None),
        (zone, False, {"rects": [[0.2, 0.2, 0.7, 0.7]]}),
        (zone, False, None),
    )]


def test_the_experimental_tasks_feedback_is_said_in_the_readers_language(app) -> None:
    from middleware.i18n import translated

    feedbacks = _task_feedbacks()
    assert any("Rubric:" in text for text in feedbacks) and any("IoU" in text for text in feedbacks)
    with app.test_request_context("/", headers=SPANISH):
        spanish = [translated(text) for text in feedbacks]
    with app.test_request_context("/", headers=ENGLISH):
        assert [translated(text) for text in feedbacks] == feedbacks  # English as stored
    english_words = re.compile(r"\b(the|ended|travelled|needs|wall|reported|was|zone|marked|of|points|Rubric|"
                               r"Nothing|recorded|precision|recall)\b")
    for text, said in zip(feedbacks, spanish, strict=True):
        assert not english_words.search(said), f"{text!r} -> {said!r}"
        assert not re.search(r"\d\.\d", said), f"a decimal point left in {said!r}"
    assert spanish[0] == "El robot terminó a 0,073 m de (1,5; 0,5). Rúbrica: 100 % de los puntos."
