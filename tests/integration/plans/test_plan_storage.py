"""Stored plans on SQLite and PostgreSQL: versions, sharing with a course, copy, export and import, and who may
read, change or run which plan (a private plan is a 404 to others, a shared one is read-only: 403 on change)."""

from __future__ import annotations

import json

from tests.integration.plans.conftest import PlansLab, api, upload

GOOD = 'say "hello"\ndrive 0.2 0 for 1s\n'
BROKEN = 'say "hello"\ndrive 0.2 0 for 1s\nrepeat 0 {\n  wait 1s\n}\nfly_to 1 2\n'


def _plans_rows(lab: PlansLab) -> list[tuple[object, ...]]:
    from sqlalchemy import select

    from middleware.db import session_factory
    from middleware.models import PlanVersion, StoredPlan

    with session_factory(lab.server.app)() as session:
        plans = session.execute(select(StoredPlan.id, StoredPlan.name, StoredPlan.owner_id,
                                       StoredPlan.shared_course_id, StoredPlan.latest_version)).all()
        versions = session.execute(select(PlanVersion.plan_id, PlanVersion.version, PlanVersion.text)).all()
    return sorted(plans) + sorted(versions)


def test_every_save_is_a_version_and_old_versions_stay_readable(plans_lab: PlansLab) -> None:
    ann = plans_lab.client("student1")
    status, body = api(ann, "POST", "/api/plans", {"name": "square", "text": GOOD})
    assert status == 201, body
    plan = body["plan"]
    assert plan["version"] == 1 and plan["mine"] and plan["plan"]["format"] == "telelab-plan/1"
    assert plan["summary"]["steps"] == 2
    status, body = api(ann, "PUT", f"/api/plans/{plan['id']}", {"text": GOOD + "wait 2s\n"})
    assert status == 200 and body["plan"]["version"] == 2 and body["plan"]["latest_version"] == 2
    assert [v["version"] for v in body["plan"]["versions"]] == [2, 1]
    status, body = api(ann, "GET", f"/api/plans/{plan['id']}?version=1")
    assert status == 200 and body["plan"]["text"] == GOOD
    status, listing = api(ann, "GET", "/api/plans")
    assert [(p["name"], p["latest_version"]) for p in listing["plans"]] == [("square", 2)]
    status, body = api(ann, "GET", f"/api/plans/{plan['id']}?version=9")
    assert status == 404 and body["error"]["field"] == "version"


def test_a_plan_with_errors_is_refused_with_every_error_on_its_line_and_nothing_stored(plans_lab: PlansLab) -> None:
    ann = plans_lab.client("student1")
    status, body = api(ann, "POST", "/api/plans/check", {"text": BROKEN})
    assert status == 200 and body["valid"] is False
    lines = sorted({error["line"] for error in body["errors"]})
    assert 3 in lines and 6 in lines, body["errors"]
    assert all(error["message"] for error in body["errors"])
    before = _plans_rows(plans_lab)
    status, body = api(ann, "POST", "/api/plans", {"name": "broken", "text": BROKEN})
    assert status == 400 and body["error"]["code"] == "invalid_plan"
    assert {error["line"] for error in body["errors"]} >= {3, 6}
    assert _plans_rows(plans_lab) == before


def test_a_skill_that_does_not_drive_the_wheels_is_refused_where_it_is_written(plans_lab: PlansLab) -> None:
    """The skill server runs only motor skills in a plan, so Check says so on the line, not the run later."""
    ann = plans_lab.client("student1")
    status, body = api(ann, "POST", "/api/plans/check", {"text": 'say "map it"\nenvironment_modelling\n'})
    assert status == 200 and body["valid"] is False
    (error,) = body["errors"]
    assert error["line"] == 2 and "skills a plan can run" in error["message"]
    assert "go_to_goal" in error["message"] and "environment_modelling" not in error["message"].split(":", 2)[-1]


def test_a_private_plan_is_a_404_to_another_student_and_a_shared_one_is_read_only(plans_lab: PlansLab) -> None:
    ann, bob, tutor = (plans_lab.client(name) for name in ("student1", "student2", "tutor1"))
    status, body = api(ann, "POST", "/api/plans", {"name": "mine", "text": GOOD})
    private_id = body["plan"]["id"]
    for method, path, payload in [("GET", f"/api/plans/{private_id}", None),
                                  ("PUT", f"/api/plans/{private_id}", {"text": GOOD}),
                                  ("GET", f"/api/plans/{private_id}/export", None),
                                  ("POST", f"/api/plans/{private_id}/copy", {}),
                                  ("POST", f"/api/plans/{private_id}/runs", {"target": "lab-1"}),
                                  ("DELETE", f"/api/plans/{private_id}", None)]:
        status, body = api(bob, method, path, payload)
        assert status == 404 and body["error"]["code"] == "unknown_plan", (method, path, body)
    assert bob.request("GET", f"/plans/{private_id}")[0] == 404
    # A student cannot share; a tutor shares with a course they teach, and its students read it.
    status, body = api(ann, "PUT", f"/api/plans/{private_id}/share", {"course_id": plans_lab.course})
    assert status == 403
    status, body = api(tutor, "POST", "/api/plans", {"name": "lesson-plan", "text": GOOD})
    shared_id = body["plan"]["id"]
    status, body = api(tutor, "PUT", f"/api/plans/{shared_id}/share", {"course_id": plans_lab.other_course})
    assert status == 404 and body["error"]["field"] == "course_id"
    status, body = api(tutor, "PUT", f"/api/plans/{shared_id}/share", {"course_id": plans_lab.course})
    assert status == 200 and body["plan"]["shared_with"]["code"] == "ROB1"
    status, body = api(bob, "GET", f"/api/plans/{shared_id}")
    assert status == 200 and body["plan"]["mine"] is False and body["plan"]["text"] == GOOD
    before = _plans_rows(plans_lab)
    for method, path, payload in [("PUT", f"/api/plans/{shared_id}", {"text": GOOD + "wait 1s\n"}),
                                  ("PUT", f"/api/plans/{shared_id}/share", {"course_id": None}),
                                  ("DELETE", f"/api/plans/{shared_id}", None)]:
        status, body = api(bob, method, path, payload)
        assert status == 403 and body["error"]["code"] == "read_only", (method, body)
    assert _plans_rows(plans_lab) == before
    # A student of another course does not see it at all.
    outsider = plans_lab.client("student3")
    assert api(outsider, "GET", f"/api/plans/{shared_id}")[0] == 404
    assert api(outsider, "GET", "/api/plans")[1]["plans"] == []
    # Copying makes it the student's own, to change.
    status, body = api(bob, "POST", f"/api/plans/{shared_id}/copy", {})
    assert status == 201 and body["plan"]["mine"] and body["plan"]["name"] == "lesson-plan"
    copy_id = body["plan"]["id"]
    assert api(bob, "PUT", f"/api/plans/{copy_id}", {"text": GOOD + "wait 1s\n"})[0] == 200
    status, body = api(bob, "POST", f"/api/plans/{shared_id}/copy", {})
    assert status == 201 and body["plan"]["name"] == "lesson-plan-2"
    status, listing = api(bob, "GET", "/api/plans")
    assert {(p["name"], p["mine"]) for p in listing["plans"]} == {("lesson-plan", True), ("lesson-plan-2", True),
                                                                  ("lesson-plan", False)}


def test_export_then_import_gives_the_same_plan_and_a_bad_file_names_its_line(plans_lab: PlansLab) -> None:
    ann = plans_lab.client("student1")
    status, body = api(ann, "POST", "/api/plans", {"name": "export-me", "text": GOOD})
    plan = body["plan"]
    status, exported = api(ann, "GET", f"/api/plans/{plan['id']}/export?format=json")
    assert status == 200 and 'filename="export-me.json"' in exported["headers"]["Content-Disposition"]
    assert json.loads(exported["body"]) == plan["plan"]
    status, text = api(ann, "GET", f"/api/plans/{plan['id']}/export?format=txt")
    assert status == 200 and text["body"] == GOOD
    status, body = upload(ann, "/api/plans/import", "again.json", exported["body"].encode())
    assert status == 201 and body["plan"]["name"] == "again" and body["plan"]["plan"] == plan["plan"]
    status, body = upload(ann, "/api/plans/import", "from-text.txt", GOOD.encode(), {"name": "typed"})
    assert status == 201 and body["plan"]["name"] == "typed" and body["plan"]["text"] == GOOD
    before = _plans_rows(plans_lab)
    status, body = upload(ann, "/api/plans/import", "bad.json", b'{\n  "format": "telelab-plan/1",\n  "steps": [,]\n}')
    assert status == 400 and body["error"]["field"] == "file" and body["error"]["message"].startswith("line 3")
    status, body = upload(ann, "/api/plans/import", "bad.txt", BROKEN.encode())
    assert status == 400 and body["error"]["code"] == "invalid_plan" and 3 in {e["line"] for e in body["errors"]}
    for name, content in [("big.txt", b"wait 1s\n" * 10_000), ("plan.exe", b"wait 1s"), ("latin.txt", b"say \"\xe9\""),
                          ("deep.json", b"[" * 5000), ("nul.txt", b"say \"a\x00\"")]:
        status, body = upload(ann, "/api/plans/import", name, content)
        assert status == 400 and body["error"]["field"] == "file", (name, body)
    assert _plans_rows(plans_lab) == before


def test_hostile_fields_are_refused_naming_them_and_change_nothing(plans_lab: PlansLab) -> None:
    ann = plans_lab.client("student1")
    status, body = api(ann, "POST", "/api/plans", {"name": "keep", "text": GOOD})
    plan_id = body["plan"]["id"]
    before = _plans_rows(plans_lab)
    for method, path, payload, field in [
            ("POST", "/api/plans", {"name": "has space", "text": GOOD}, "name"),
            ("POST", "/api/plans", {"name": "x" * 65, "text": GOOD}, "name"),
            ("POST", "/api/plans", {"name": ["x"], "text": GOOD}, "name"),
            ("POST", "/api/plans", {"name": "keep", "text": GOOD}, "name"),
            ("POST", "/api/plans", {"name": "ok", "text": 3}, "text"),
            ("POST", "/api/plans", {"name": "ok", "text": "wait 1s\n" * 9000}, "text"),
            ("PUT", f"/api/plans/{plan_id}", {"text": GOOD, "name": "../../etc"}, "name"),
            ("PUT", f"/api/plans/{plan_id}/share", {"course_id": "1"}, "course_id"),
            ("PUT", f"/api/plans/{plan_id}/share", {}, "course_id"),
            ("GET", f"/api/plans/{plan_id}?version=-1", None, "version"),
            ("GET", f"/api/plans/{plan_id}?version=99999999999999999999", None, "version"),
            ("GET", f"/api/plans/{plan_id}/export?format=exe", None, "format"),
            ("POST", f"/api/plans/{plan_id}/runs", {"target": ""}, "target"),
            ("POST", f"/api/plans/{plan_id}/runs", {"target": "nowhere"}, "target"),
            ("POST", f"/api/plans/{plan_id}/runs", {"target": "practice", "from_dock": "yes"}, "from_dock")]:
        status, body = api(ann, method, path, payload)
        assert 400 <= status < 500 and body["error"]["field"] == field, (method, path, payload, status, body)
    assert api(ann, "GET", "/api/plans/99999")[0] == 404
    assert api(ann, "GET", "/api/plans/99999999999")[0] == 404
    assert _plans_rows(plans_lab) == before


def test_a_plan_used_as_a_skill_is_a_panel_of_its_owners_consoles_only(plans_lab: PlansLab) -> None:
    ann, bob = plans_lab.client("student1"), plans_lab.client("student2")
    status, body = api(ann, "POST", "/api/plans", {"name": "as-skill", "text": GOOD})
    plan_id = body["plan"]["id"]
    assert body["plan"]["console_skill"] is False
    before = _plans_rows(plans_lab)
    status, body = api(ann, "PUT", f"/api/plans/{plan_id}/skill", {"console_skill": "yes"})
    assert status == 400 and body["error"]["field"] == "console_skill"
    assert api(bob, "PUT", f"/api/plans/{plan_id}/skill", {"console_skill": True})[0] == 404
    assert _plans_rows(plans_lab) == before
    status, body = api(ann, "PUT", f"/api/plans/{plan_id}/skill", {"console_skill": True})
    assert status == 200 and body["plan"]["console_skill"] is True
    status, body = api(ann, "GET", "/api/robots/lab-1/panels")
    panel = next(p for p in body["panels"] if p["kind"] == "plan")
    assert panel["id"] == f"plan-{plan_id}" and panel["run_url"] == f"/api/plans/{plan_id}/runs"
    assert panel["skill"] == "plan:as-skill" and panel["tab"] == "navigate"
    status, body = api(bob, "GET", "/api/robots/lab-1/panels")
    assert not [p for p in body["panels"] if p["kind"] == "plan"]
    assert api(ann, "PUT", f"/api/plans/{plan_id}/skill", {"console_skill": False})[1]["plan"]["console_skill"] is False
    status, body = api(ann, "GET", "/api/robots/lab-1/panels")
    assert not [p for p in body["panels"] if p["kind"] == "plan"]
