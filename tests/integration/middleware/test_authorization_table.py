"""Every cell of the authorization table in middleware/README.md, through the real app on SQLite and PostgreSQL.

Each cell is "yes <status>" (the action happened) or "no <status>" (it did not); the test sends the request as
that column's person and checks both the status and the effect in the database. The README's table must be
this one, so the written rules and the tested ones cannot drift apart.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from urllib.request import Request

import pytest
from sqlalchemy import func, select, update
from sqlalchemy.orm import Session

from middleware.db import session_factory
from middleware.models import Course, CourseMembership
from middleware.models.experiment import Trial, VideoDelay
from middleware.models.teaching import GuidedSession, Lesson, Tour
from middleware.teaching.demo_content import DEMO_CUES, DEMO_TOURS
from tests.conftest import STUDENT_PASSWORD, LabClient, LiveServer, _let_go, make_test_app

README = Path(__file__).resolve().parents[3] / "middleware" / "README.md"
COLUMNS = ("anonymous", "student", "tutor of the course", "tutor of another course", "admin")
ACTORS = (None, "stu_a", "tut_a", "tut_b", "adm")
VIDEO = "intro.webm"


@dataclass
class Lab:
    """The served app and the ids of what the rows act on: course A (tutors tut_a and lead_a, student stu_a),
    course B (tutor tut_b), an admin, a tour and a lesson written by lead_a, and a tour with no author."""

    server: LiveServer
    ids: dict[str, int]

    def session(self) -> Session:
        return session_factory(self.server.app)()

    def client(self, username: str | None) -> LabClient:
        """A client logged in as username (None: nobody)."""
        client = LabClient(self.server.url)
        if username is not None:
            assert client.login(username, STUDENT_PASSWORD) == 302
        return client

    def running_class(self, course: str, tutor: str) -> int:
        """Ends every class on lab-1 and starts one of course led by tutor; its id."""
        with self.session() as session, session.begin():
            session.execute(update(GuidedSession).values(ended_at=GuidedSession.started_at))
            live = GuidedSession(tour_id=self.ids["tour"], robot_name="lab-1", tutor_id=self.ids[tutor],
                                 course_id=self.ids[course], step_index=0, control_user_id=self.ids[tutor],
                                 version=1)
            session.add(live)
        return live.id


def call(client: LabClient, method: str, path: str, body: object | None = None) -> tuple[int, str]:
    """(status, text) of a JSON request carrying a page's CSRF token, as the pages' scripts send it."""
    headers = {"Accept": "application/json", "Content-Type": "application/json"}
    if method != "GET":
        logged_in = client.request("GET", "/experiment")[0] == 200
        headers["X-CSRFToken"] = client.csrf_token("/experiment" if logged_in else "/login")
    request = Request(client.base_url + path, data=None if body is None else json.dumps(body).encode(),
                      method=method, headers=headers)
    try:
        with client._opener.open(request, timeout=30) as response:  # noqa: SLF001
            return response.status, response.read().decode()
    except Exception as error:  # urllib raises for 3xx-5xx; they are answers here
        if not hasattr(error, "code"):
            raise
        return error.code, error.read().decode()


def _tour_body(title: str) -> dict[str, object]:
    return {**DEMO_TOURS[0], "slug": "shared-tour", "title": title}


# --- the rows: each runs the action as one person and tells whether it happened ---------------------------


def start_class(lab: Lab, client: LabClient, actor: str | None, body: dict[str, object]) -> tuple[int, bool]:
    with lab.session() as session, session.begin():
        session.execute(update(GuidedSession).values(ended_at=GuidedSession.started_at))
    status, _ = call(client, "POST", f"/api/tours/{lab.ids['tour']}/sessions", {"robot": "lab-1", **body})
    with lab.session() as session:
        live = session.scalar(select(GuidedSession).where(GuidedSession.ended_at.is_(None)))
        happened = live is not None and live.tutor_id == lab.ids.get(actor or "", -1)
        if body.get("override"):
            happened = happened and live is not None and live.priority_override_by_id == live.tutor_id
    return status, happened


def start_for_course_a(lab: Lab, client: LabClient, actor: str | None) -> tuple[int, bool]:
    return start_class(lab, client, actor, {"course_id": lab.ids["course_a"]})


def start_without_course(lab: Lab, client: LabClient, actor: str | None) -> tuple[int, bool]:
    return start_class(lab, client, actor, {"course_id": None})


def start_with_override(lab: Lab, client: LabClient, actor: str | None) -> tuple[int, bool]:
    return start_class(lab, client, actor, {"course_id": lab.ids["course_a"], "override": True})


def start_over_course_a_class(lab: Lab, client: LabClient, actor: str | None) -> tuple[int, bool]:
    running = lab.running_class("course_a", "lead_a")
    own_course = lab.ids["course_b" if actor in ("tut_b", "adm") else "course_a"]
    status, _ = call(client, "POST", f"/api/tours/{lab.ids['tour']}/sessions",
                     {"robot": "lab-1", "course_id": own_course})
    with lab.session() as session:
        return status, session.get(GuidedSession, running).ended_at is not None  # type: ignore[union-attr]


def class_action(action: dict[str, object], happened: Callable[[GuidedSession, Lab], bool]):
    def run(lab: Lab, client: LabClient, _actor: str | None) -> tuple[int, bool]:
        running = lab.running_class("course_a", "lead_a")
        status, _ = call(client, "POST", f"/api/tour-sessions/{running}", action)
        with lab.session() as session:
            return status, happened(session.get(GuidedSession, running), lab)  # type: ignore[arg-type]
    return run


def see_class_controls(lab: Lab, client: LabClient, _actor: str | None) -> tuple[int, bool]:
    running = lab.running_class("course_a", "lead_a")
    status, _, text = client.request("GET", f"/tours/sessions/{running}")
    return status, 'data-tutor="true"' in text


def follow_class_page(lab: Lab, client: LabClient, _actor: str | None) -> tuple[int, bool]:
    running = lab.running_class("course_a", "lead_a")
    status, _, text = client.request("GET", f"/tours/sessions/{running}")
    return status, status == 200 and f'data-session-id="{running}"' in text


def read_class_state(lab: Lab, client: LabClient, _actor: str | None) -> tuple[int, bool]:
    running = lab.running_class("course_a", "lead_a")
    status, text = call(client, "GET", f"/api/tour-sessions/{running}")
    return status, status == 200 and json.loads(text).get("id") == running


def set_delay_of(target: str):
    def run(lab: Lab, client: LabClient, actor: str | None) -> tuple[int, bool]:
        with lab.session() as session, session.begin():
            session.query(VideoDelay).delete()
        status, _ = call(client, "PUT", f"/api/experiment/delays/{target}", {"delay_s": 2})
        with lab.session() as session:
            row = session.get(VideoDelay, lab.ids[target])
            return status, row is not None and row.delay_s == 2 and row.set_by_id == lab.ids.get(actor or "")
    return run


def read_results_json(lab: Lab, client: LabClient, _actor: str | None) -> tuple[int, bool]:
    status, text = call(client, "GET", "/api/experiment/results")
    listed = status == 200 and any(t["username"] == "stu_a" for t in json.loads(text)["trials"])
    return status, listed


def read_results_csv(lab: Lab, client: LabClient, _actor: str | None) -> tuple[int, bool]:
    status, _, text = client.request("GET", "/experiment/results.csv")
    return status, status == 200 and "stu_a" in text


def overwrite(kind: str, key: str):
    model = Tour if kind == "tour" else Lesson

    def run(lab: Lab, client: LabClient, actor: str | None) -> tuple[int, bool]:
        title = f"Edited by {actor}"
        body = _tour_body(title) if kind == "tour" else {"title": title, "video_name": VIDEO, "cues": DEMO_CUES}
        if key == "demo_tour":
            body["slug"] = "demo-tour"
        status, _ = call(client, "PUT", f"/api/{kind}s/{lab.ids[key]}", body)
        with lab.session() as session:
            return status, session.get(model, lab.ids[key]).title == title  # type: ignore[union-attr]
    return run


def open_page(path: str, shows: str = ""):
    def run(lab: Lab, client: LabClient, _actor: str | None) -> tuple[int, bool]:
        status, _, text = client.request("GET", path.format(**lab.ids))
        return status, status == 200 and shows.format(**lab.ids) in text
    return run


ROWS: dict[str, tuple[Callable[[Lab, LabClient, str | None], tuple[int, bool]], tuple[str, ...]]] = {
    "Start a live class for course A": (
        start_for_course_a, ("no 401", "no 403", "yes 201", "no 403", "yes 201")),
    "Start a live class for no course": (
        start_without_course, ("no 401", "no 403", "no 403", "no 403", "yes 201")),
    "Start a live class with the priority override (recorded)": (
        start_with_override, ("no 401", "no 403", "no 403", "no 403", "yes 201")),
    "Start a class on a robot where course A's class runs (ends it)": (
        start_over_course_a_class, ("no 401", "no 403", "yes 201", "no 409", "yes 201")),
    "End course A's class (led by another tutor of A)": (
        class_action({"action": "end"}, lambda live, _lab: live.ended_at is not None),
        ("no 401", "no 403", "yes 200", "no 403", "yes 200")),
    "Hand control in course A's class to a student": (
        class_action({"action": "control", "user": "stu_a"},
                     lambda live, lab: live.control_user_id == lab.ids["stu_a"]),
        ("no 401", "no 403", "yes 200", "no 403", "yes 200")),
    "Hand control in course A's class to someone not in course A": (
        class_action({"action": "control", "user": "tut_b"},
                     lambda live, lab: live.control_user_id == lab.ids["tut_b"]),
        ("no 401", "no 403", "no 403", "no 403", "no 403")),
    "See the tutor's controls on course A's class page": (
        see_class_controls, ("no 302", "no 200", "yes 200", "no 403", "yes 200")),
    "Follow course A's class (its page)": (
        follow_class_page, ("no 302", "yes 200", "yes 200", "no 403", "yes 200")),
    "Read course A's class state (JSON)": (
        read_class_state, ("no 401", "yes 200", "yes 200", "no 403", "yes 200")),
    "See course A on the lead-a-class page": (
        open_page("/tours/{tour}/lead", 'value="{course_a}"'), ("no 302", "no 403", "yes 200", "no 200", "yes 200")),
    "Set the video delay of a student of course A": (
        set_delay_of("stu_a"), ("no 401", "no 403", "yes 200", "no 403", "yes 200")),
    "Set an admin's video delay": (
        set_delay_of("adm"), ("no 401", "no 403", "no 403", "no 403", "yes 200")),
    "Read course A's experiment results (JSON)": (
        read_results_json, ("no 401", "no 403", "yes 200", "no 200", "yes 200")),
    "Download course A's experiment results (CSV)": (
        read_results_csv, ("no 302", "no 403", "yes 200", "no 200", "yes 200")),
    "Open the editor of a tour by a tutor of course A": (
        open_page("/tours/{tour}/edit"), ("no 302", "no 403", "yes 200", "no 403", "yes 200")),
    "Overwrite a tour by a tutor of course A": (
        overwrite("tour", "tour"), ("no 401", "no 403", "yes 200", "no 403", "yes 200")),
    "Overwrite a tour with no author (demo content)": (
        overwrite("tour", "demo_tour"), ("no 401", "no 403", "no 403", "no 403", "yes 200")),
    "Overwrite a lesson by a tutor of course A": (
        overwrite("lesson", "lesson"), ("no 401", "no 403", "yes 200", "no 403", "yes 200")),
}


def _seed(session: Session) -> dict[str, int]:
    from middleware.auth.services import create_user

    people = {name: create_user(session, name, role, STUDENT_PASSWORD) for name, role in (
        ("stu_a", "student"), ("tut_a", "tutor"), ("lead_a", "tutor"), ("tut_b", "tutor"), ("adm", "admin"))}
    course_a, course_b = Course(code="A", title="Course A"), Course(code="B", title="Course B")
    session.add_all([course_a, course_b])
    session.flush()
    session.add_all([CourseMembership(course_id=course_a.id, user_id=people[name].id, role=role)
                     for name, role in (("stu_a", "student"), ("tut_a", "tutor"), ("lead_a", "tutor"))]
                    + [CourseMembership(course_id=course_b.id, user_id=people["tut_b"].id, role="tutor")])
    tour = Tour(slug="shared-tour", title="Shared", steps_json=json.dumps(DEMO_TOURS[0]["steps"]),
                author_id=people["lead_a"].id)
    demo = Tour(slug="demo-tour", title="Demo", steps_json=json.dumps(DEMO_TOURS[0]["steps"]))
    lesson = Lesson(slug="shared-lesson", title="Lesson", video_name=VIDEO, cues_vtt=DEMO_CUES,
                    author_id=people["lead_a"].id)
    session.add_all([tour, demo, lesson, Trial(user_id=people["stu_a"].id, course_id=course_a.id, robot_name="lab-1",
                                                course="course-A", delay_s=1.0, feedback=True, status="completed",
                                                total_time_s=42.0)])  # a trial that counts for course A
    session.commit()
    return {**{name: user.id for name, user in people.items()}, "course_a": course_a.id, "course_b": course_b.id,
            "tour": tour.id, "demo_tour": demo.id, "lesson": lesson.id}


@pytest.fixture(scope="module")
def lab(module_database_url: str, tmp_path_factory: pytest.TempPathFactory,
        skill_server_address: str) -> Iterator[Lab]:
    """The app on one database for the whole table, wired to the session's skill server (saving tours checks
    their skills). Each row first resets what it acts on (running classes, delays), so rows cannot see each
    other's effects."""

    app = make_test_app(module_database_url, f"lab-1={skill_server_address}", tmp_path_factory.mktemp("lab"))
    (Path(app.instance_path) / "lessons").mkdir(parents=True)
    (Path(app.instance_path) / "lessons" / VIDEO).write_bytes(b"\x1a\x45\xdf\xa3 not really a video")
    with session_factory(app)() as session:
        ids = _seed(session)
    server = LiveServer(app)
    try:
        yield Lab(server, ids)
    finally:
        server.stop()
        _let_go(app)  # its ticker, links, farm and practice keeper
        session_factory(app).kw["bind"].dispose()  # before the PostgreSQL database is dropped


@pytest.mark.parametrize("action", list(ROWS))
def test_every_cell_of_the_authorization_table(lab: Lab, action: str) -> None:
    run, expected = ROWS[action]
    seen = []
    for actor in ACTORS:
        client = lab.client(actor)
        try:
            status, happened = run(lab, client, actor)
        finally:
            client.close()
        seen.append(f"{'yes' if happened else 'no'} {status}")
    assert dict(zip(COLUMNS, seen, strict=True)) == dict(zip(COLUMNS, expected, strict=True))


HOSTILE_CLASS_STARTS = [("course_id", 10**30), ("course_id", -1), ("course_id", True), ("course_id", "A"),
                        ("course_id", 999_999), ("override", "yes"), ("override", 1), ("robot", "nowhere"),
                        ("robot", None)]


def test_a_class_start_refuses_hostile_fields_naming_them(lab: Lab) -> None:
    client = lab.client("adm")
    with lab.session() as session:
        classes_before = session.scalar(select(func.count()).select_from(GuidedSession))
    answers = []
    for field, value in HOSTILE_CLASS_STARTS:
        body = {"robot": "lab-1", "course_id": lab.ids["course_a"], field: value}
        status, text = call(client, "POST", f"/api/tours/{lab.ids['tour']}/sessions", body)
        answers.append((status, json.loads(text)["error"]["field"]))
    assert answers == [(400, field) for field, _ in HOSTILE_CLASS_STARTS]
    with lab.session() as session:
        assert session.scalar(select(func.count()).select_from(GuidedSession)) == classes_before


def readme_table() -> dict[str, tuple[str, ...]]:
    """The rows of the README's authorization table."""
    text = README.read_text()
    section = text.split("## Authorization table", 1)[1].split("\n## ", 1)[0]
    rows = {}
    for line in section.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if line.startswith("|") and len(cells) == 6 and re.fullmatch(r"(yes|no) \d{3}", cells[1]):
            rows[cells[0]] = tuple(cells[1:])
    return rows


def test_the_readme_states_the_table_this_test_checks() -> None:
    assert readme_table() == {action: cells for action, (_run, cells) in ROWS.items()}


def test_a_class_channel_lets_in_only_those_who_may_follow_the_class(lab: Lab) -> None:
    from tests.integration.lab.test_robot_channels import closed_with, receive_json

    running = lab.running_class("course_a", "lead_a")
    for actor, allowed in (("stu_a", True), ("tut_a", True), ("adm", True), ("tut_b", False)):
        ws = lab.client(actor).websocket(f"/ws/tour-sessions/{running}")
        first = receive_json(ws)
        if allowed:
            assert first["type"] == "state" and first["id"] == running, actor
            ws.close()
        else:
            assert first["code"] == "not_in_course" and first["field"] == "session_id", actor
            assert closed_with(ws) == 4403, actor
