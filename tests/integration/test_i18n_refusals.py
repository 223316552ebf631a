"""A student's and a tutor's refusals in their language, over HTTP on the live app: with Accept-Language: es (or the
person's language preference) a booking refused, a field missing, a test not open yet, a chat message too long, a
course not one's own and an address with nothing at it answer in Spanish, with the same code and field; without
either, in English as before."""

from __future__ import annotations

from datetime import UTC, datetime, timedelta

from tests.conftest import LabClient
from tests.integration.bookings.conftest import api, client_as, course_people

__all__ = ["client_as", "course_people"]

SPANISH = {"Accept-Language": "es-ES,es;q=0.9"}


def _slot(days: int) -> str:
    day = datetime.now(UTC).replace(hour=9, minute=0, second=0, microsecond=0) + timedelta(days=days)
    return day.isoformat().replace("+00:00", "Z")


def _refusals(student: LabClient, tutor2: LabClient, course_id: int, exam_id: int,
              headers: dict[str, str] | None) -> dict[str, tuple[int, dict]]:
    return {
        "past slot": api(student, "POST", "/api/bookings",
                          {"robot_name": "lab-1", "starts_at": _slot(-1), "duration_min": 30}, headers),
        "no start": api(student, "POST", "/api/bookings", {"robot_name": "lab-1"}, headers),
        "not open": api(student, "POST", f"/api/exams/{exam_id}/attempts", {}, headers),
        "too long": api(student, "POST", "/api/robots/lab-1/chat", {"body": "x" * 501}, headers),
        "not yours": api(tutor2, "POST", f"/api/courses/{course_id}/exams",
                          {"title": "Quiz", "kind": "theory"}, headers),
    }


def test_a_students_and_a_tutors_refusals_speak_spanish_when_asked_and_english_otherwise(client_as,
                                                                                         course_people) -> None:
    tutor, student, tutor2 = client_as("tutor1"), client_as("student1"), client_as("tutor2")
    course_id = course_people["course"]
    status, body = api(tutor, "POST", f"/api/courses/{course_id}/questions",
                        {"kind": "single", "prompt": "Odometry drifts?", "choices": ["no", "yes"], "correct": 1})
    assert status == 201, body
    question_id = body["question"]["id"]
    opens = datetime.now(UTC) + timedelta(days=2)
    status, body = api(tutor, "POST", f"/api/courses/{course_id}/exams", {
        "title": "Midterm", "kind": "theory", "opens_at": opens.isoformat(),
        "closes_at": (opens + timedelta(hours=1)).isoformat(), "duration_s": 600, "question_ids": [question_id]})
    assert status == 201, body
    exam_id = body["exam"]["id"]

    english = _refusals(student, tutor2, course_id, exam_id, None)
    spanish = _refusals(student, tutor2, course_id, exam_id, SPANISH)
    said = {what: answer["error"]["message"] for what, (_, answer) in spanish.items()}
    assert said == {
        "past slot": "Esa franja ya ha empezado; elige una en el futuro.",
        "no start": "starts_at es obligatorio.",
        "not open": "Esta prueba aún no está abierta.",
        "too long": "Un mensaje puede tener como mucho 500 caracteres; este tiene 501.",
        "not yours": "Solo puedes gestionar los cursos que impartes.",
    }
    assert {what: answer["error"]["message"] for what, (_, answer) in english.items()} == {
        "past slot": "That slot has already started; choose one in the future.",
        "no start": "starts_at is required.",
        "not open": "This test is not open yet.",
        "too long": "A message may have at most 500 characters; this has 501.",
        "not yours": "You can manage only the courses you teach.",
    }
    for what, (status, answer) in spanish.items():  # the same refusal: only its sentence changes
        english_status, english_answer = english[what]
        assert status == english_status and 400 <= status < 500
        assert {k: v for k, v in answer["error"].items() if k != "message"} == {
            k: v for k, v in english_answer["error"].items() if k != "message"}


def test_an_invitation_link_that_cannot_be_used_says_why_in_the_browsers_language(client_as) -> None:
    visitor = client_as(None)
    status, _, page = visitor.request("GET", "/join/not-a-token", headers=SPANISH)
    assert status == 404 and "Este enlace de invitación no es válido" in page and "pide a tu tutor" in page
    status, _, page = visitor.request("GET", "/join/not-a-token")
    assert status == 404 and "This invitation link is not valid" in page


def test_the_persons_language_preference_speaks_spanish_without_the_browser_asking(client_as) -> None:
    student = client_as("student1")
    assert api(student, "PUT", "/api/me/preferences/language", {"value": "es"})[0] == 200
    status, answer = api(student, "POST", "/api/bookings", {"robot_name": "lab-1", "starts_at": _slot(1),
                                                             "duration_min": 300})
    assert (status, answer["error"]["message"]) == (400, "Una reserva puede durar como mucho 4 horas.")
    status, answer = api(student, "POST", "/api/robots/lab-1/chat", [])
    assert status == 400 and answer["error"]["message"] in ("Envía un objeto JSON.",
                                                            "Envía el mensaje como un objeto JSON con un body.")
    status, _, page = student.request("GET", "/no-such-page")
    assert status == 404 and "No encontrado" in page and "No hay nada en esta dirección." in page
    assert api(student, "PUT", "/api/me/preferences/language", {"value": "en"})[0] == 200
    status, _, page = student.request("GET", "/no-such-page")
    assert status == 404 and "Not Found" in page and "There is nothing at this address." in page


def test_a_channels_messages_hold_no_database_connection_to_learn_the_language(app) -> None:
    """A socket's context lives as long as the socket: a message taken never looks the language up, and a refusal
    looks the person's preference up in a session closed at once (a drive socket held a connection otherwise, and
    a restarted worker's sockets ran the pool dry)."""
    from flask import g
    from flask_login import login_user
    from sqlalchemy import select

    from middleware.db import session_factory
    from middleware.models import User, UserPreference
    from middleware.validation import InvalidInput, parse_message

    factory = session_factory(app)
    with factory() as session:
        student = session.scalar(select(User).where(User.username == "student1"))
        session.add(UserPreference(user_id=student.id, key="language", value_json='"es"'))
        session.commit()
    pool = factory.kw["bind"].pool
    with app.test_request_context("/ws/robots/lab-1/drive"):
        login_user(student)
        assert parse_message('{"type": "drive"}', ("drive", "stop"), 100) == {"type": "drive"}
        assert "db_session" not in g
        try:
            parse_message('{"type": "fly"}', ("drive", "stop"), 100)
        except InvalidInput as refused:
            assert refused.message == "type debe ser 'drive' o 'stop'."
        else:
            raise AssertionError("a type the channel does not take was accepted")
        assert "db_session" not in g and pool.checkedout() == 0


def test_a_booking_is_written_with_the_days_and_months_of_the_pages_language(client_as) -> None:
    from babel.dates import format_datetime

    student = client_as("student1")
    status, answer = api(student, "POST", "/api/bookings", {"robot_name": "lab-1", "starts_at": _slot(1),
                                                             "duration_min": 30})
    assert status == 201, answer
    starts = datetime.fromisoformat(_slot(1))
    _, _, page = student.request("GET", "/bookings?tz=UTC", headers=SPANISH)
    spanish = format_datetime(starts, "EEE dd MMM, HH:mm", tzinfo=UTC, locale="es")
    assert spanish in page and starts.strftime("%a %d %b") not in page, spanish
    _, _, page = student.request("GET", "/bookings?tz=UTC")
    assert starts.strftime("%a %d %b, %H:%M") in page


def test_the_refusals_of_the_labs_other_areas_speak_spanish_with_the_same_code_and_field(client_as,
                                                                                        course_people) -> None:
    """Recordings, the experiment's protocol, a robot's settings, the practice robot's commands, the teaching wall and
    the login check answer in Spanish when asked, in English otherwise; only the sentence changes."""
    student, tutor, tutor2, anonymous = client_as("student1"), client_as("tutor1"), client_as("tutor2"), client_as(None)
    course_id = course_people["course"]
    asked = {
        "recording": (student, "GET", "/api/recordings/999999", None),
        "protocol": (tutor2, "PUT", f"/api/experiment/protocols/{course_id}", {"learning_s": 60}),
        "settings": (student, "POST", "/api/robots/lab-1/limits", {}),
        "practice": (student, "POST", "/api/practice/commands", {"command": {"stop": True}}),
        "wall": (tutor, "POST", f"/api/courses/{course_id}/class-wall", {"action": "stop_all"}),
        "login": (anonymous, "GET", "/api/recordings", None),
    }
    english = {what: api(client, method, path, body) for what, (client, method, path, body) in asked.items()}
    spanish = {what: api(client, method, path, body, SPANISH) for what, (client, method, path, body) in asked.items()}
    assert {what: answer["error"]["message"] for what, (_, answer) in spanish.items()} == {
        "recording": "No existe esa grabación.",
        "protocol": "Solo los tutores del curso fijan su protocolo experimental.",
        "settings": "Envía al menos uno de estos valores por encima de 0: max_linear_mps, max_angular_radps, "
                    "watchdog_s.",
        "practice": "Arranca primero tu robot de prácticas.",
        "wall": "No hay ninguna sesión de clase abierta para este curso; inicia una primero.",
        "login": "Inicia sesión primero; puede que tu sesión haya terminado.",
    }
    assert {what: answer["error"]["message"] for what, (_, answer) in english.items()} == {
        "recording": "There is no such recording.",
        "protocol": "Only the course's tutors set its experiment protocol.",
        "settings": "Send at least one of max_linear_mps, max_angular_radps, watchdog_s above 0.",
        "practice": "Start your practice robot first.",
        "wall": "No class session is open for this course; start one first.",
        "login": "Log in first; your session may have ended.",
    }
    for what, (status, answer) in spanish.items():
        assert status == english[what][0] and 400 <= status < 500, (what, status, answer)
        assert {k: v for k, v in answer["error"].items() if k != "message"} == {
            k: v for k, v in english[what][1]["error"].items() if k != "message"}, what
