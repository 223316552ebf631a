"""Deep linking of every kind issue 29 names, on the seeded lab: an instructor places a robot console, a pool, a
lesson, a tour, a test, a Python exercise and the class session in the LMS course in one answer, signed with the
tool's key; a learner (and, for the class session, the instructor) then opens each placed link from the LMS and
lands on its page, which they may read."""

from __future__ import annotations

import contextlib
import html
import re
from collections.abc import Iterator
from pathlib import Path
from urllib.parse import urlencode, urlsplit
from urllib.request import Request, urlopen

import pytest

from tests.conftest import LabClient, LiveServer
from tests.hardening.conftest import seeded_lab, stop_lab
from tests.integration.bookings.conftest import api
from tests.integration.lti.conftest import launch, register
from tests.integration.lti.platform import INSTRUCTOR, LEARNER, LmsPlatform
from tests.integration.lti.test_services import _inputs

CONTENT_ITEMS = "https://purl.imsglobal.org/spec/lti-dl/claim/content_items"


@pytest.fixture(scope="module")
def seeded(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[LiveServer, LmsPlatform]]:
    """The demo lab (robots unreachable; its tours, its lessons, its exercises) served, and a registered LMS."""
    from middleware.teaching.demo_content import DEMO_VIDEO

    tmp = tmp_path_factory.mktemp("deep-link-kinds")
    videos = tmp / "instance" / "lessons"
    videos.mkdir(parents=True)
    (videos / DEMO_VIDEO).write_bytes(b"\x1a\x45\xdf\xa3")  # the demo lessons are added once their video exists
    app = seeded_lab(f"sqlite:///{tmp / 'lab.sqlite3'}", Path(tmp))
    server = LiveServer(app)
    platform = LmsPlatform(tool_url=server.url)
    with contextlib.ExitStack() as undo:  # in reverse: the lab's work, its server, the LMS
        undo.callback(stop_lab, app)
        undo.callback(server.stop)
        undo.callback(platform.stop)
        register(server, platform)
        yield server, platform


def _offered(picker: str) -> dict[str, str]:
    """target -> the item's label, as the picker's checkboxes offer them."""
    return {html.unescape(m.group(1)): html.unescape(re.sub(r"<[^>]+>", " ", m.group(2))).strip()
            for m in re.finditer(r'<input[^>]*name="target"[^>]*value="([^"]*)"[^>]*>(.*?)</label>', picker, re.S)}


def headers_of(client: LabClient, path: str) -> dict[str, str]:
    return client.request("GET", path)[1]


def test_each_kind_is_placed_from_the_lms_and_its_link_opens_its_page(seeded: tuple[LiveServer, LmsPlatform]) -> None:
    server, lms = seeded
    tutor = LabClient(server.url)
    assert launch(tutor, lms, "pia-instructor", [INSTRUCTOR])[0] == 303
    course = int(re.search(r'href="/courses/(\d+)"', tutor.request("GET", "/courses")[2]).group(1))
    status, question = api(tutor, "POST", f"/api/courses/{course}/questions",
                           {"kind": "text", "prompt": "Which sensor measures range?", "accepted": ["sonar"]})
    assert status == 201, question
    status, exam = api(tutor, "POST", f"/api/courses/{course}/exams",
                       {"title": "Range quiz", "kind": "quiz", "question_ids": [question["question"]["id"]]})
    assert status == 201, exam
    exam_id = exam["exam"]["id"]

    status, _, picker = launch(tutor, lms, "pia-instructor", [INSTRUCTOR], deep_link=True)
    assert status == 200, picker
    offered = _offered(picker)
    chosen = {}
    for kind, title in (("console", "lab-1"), ("pool", None), ("lesson", "First moves"),
                        ("tour", "Control directo"), ("exam", "Range quiz"), ("exercise", None), ("class", None)):
        targets = [t for t, label in offered.items() if t.startswith(kind + ":") and (title is None or title in label)]
        assert targets, f"the picker offers no {kind} {title or ''}: {sorted(offered)}"
        chosen[kind] = targets[0]
    form = _inputs(picker)
    fields = [("csrf_token", form["csrf_token"]), ("launch_id", form["launch_id"])]
    status, _, answer = tutor.request("POST", "/lti/deep-link",
                                      fields + [("target", target) for target in chosen.values()])  # type: ignore[arg-type]
    assert status == 200, answer
    action = html.unescape(re.search(r'action="([^"]+)"', answer[answer.index('id="deep-link-return"') - 200:])
                           .group(1))
    with urlopen(Request(action, data=urlencode({"JWT": _inputs(answer)["JWT"]}).encode()), timeout=10) as reply:
        assert reply.status == 200
    items = {item["custom"]["telelab_target"]: item for item in lms.deep_link_returns[-1][CONTENT_ITEMS]}
    assert set(items) == set(chosen.values())
    assert [t for t, item in items.items() if "lineItem" in item] == [chosen["exam"]]  # a test gets a column
    # A Python exercise needs a window of its own (cross-origin isolation, which no LMS frame gives); nothing else.
    assert {t: item.get("window") for t, item in items.items() if "window" in item} == {
        chosen["exercise"]: {"targetName": "_blank"}}

    # Where each placed link opens, and the page's heading the person reads there.
    learner = LabClient(server.url)
    for kind, target in chosen.items():
        status, headers, body = launch(learner, lms, "lou-learner", [LEARNER], custom=items[target]["custom"])
        assert status == 303, f"{kind}: {status} {body[:300]}"
        path = urlsplit(headers["Location"]).path
        expected = {"console": "/lab/lab-1", "pool": "/pools/", "lesson": "/lessons/", "tour": "/tours/",
                    "exam": f"/assessment/exams/{exam_id}", "exercise": "/exercises/",
                    "class": "/class"}[kind]
        assert path.startswith(expected), f"{kind} opened {path}"
        status, _, page = learner.request("GET", path)
        assert status == 200, f"{kind}: the learner may not read {path} ({status})"
        heading = re.search(r"<h1[^>]*>(.*?)</h1>", page, re.S)
        assert heading, f"{kind}: {path} has no heading"
        if kind in ("lesson", "tour", "exam", "exercise"):  # the page of the very item placed
            assert items[target]["title"] in html.unescape(page), f"{kind}: {path} is not {items[target]['title']}"
        framers = headers_of(learner, path)["Content-Security-Policy"].split("frame-ancestors ")[1].split(";")[0]
        assert lms.issuer in framers.split(), f"{kind}: {path} may not be framed by the LMS ({framers})"
    status, headers, _ = launch(tutor, lms, "pia-instructor", [INSTRUCTOR], custom=items[chosen["class"]]["custom"])
    assert status == 303 and urlsplit(headers["Location"]).path == f"/courses/{course}/class", headers["Location"]
