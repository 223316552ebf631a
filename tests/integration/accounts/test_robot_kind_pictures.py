"""Admins choose, per robot kind, the camera panel's first picture (the robot's video or the view drawn by the
browser); the console's panel list carries it to the camera panel. Checked on the live app: the admin's page and
API, what others are refused, and bad input refused with the field named; the drawn picture only for a kind whose
robots describe a scene (simulated ones: a robot standing for a real one keeps its video)."""

from __future__ import annotations

from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor

import grpc
import pytest

from protos.telelab.v1 import robot_pb2, robot_pb2_grpc
from tests.integration.bookings.conftest import api


def camera_picture(client, robot_name: str) -> dict:
    status, answer = api(client, "GET", f"/api/robots/{robot_name}/panels")
    assert status == 200, answer
    return next(panel for panel in answer["panels"] if panel["kind"] == "camera")["picture"]


def test_an_admin_makes_the_drawn_view_the_default_for_a_kind_and_the_console_hears_it(client_as,
                                                                                      course_people) -> None:
    admin, student = client_as("admin1"), client_as("student1")
    assert camera_picture(student, "lab-1") == {"kind": "lab", "default": "video", "chosen": None}
    status, kinds = api(admin, "GET", "/api/admin/robot-kinds")
    assert status == 200 and {"kind": "lab", "camera_picture": "video"} in kinds["kinds"]

    status, answer = api(admin, "PUT", "/api/admin/robot-kinds/lab/picture", {"picture": "drawn"})
    assert (status, answer) == (200, {"kind": "lab", "camera_picture": "drawn"})
    assert camera_picture(student, "lab-1") == {"kind": "lab", "default": "drawn", "chosen": None}

    # The robots page's form says the same and sets it back.
    _, _, page = admin.request("GET", "/admin/robots")
    row = page.split('data-kind="lab"', 1)[1].split("</tr>", 1)[0]
    assert '<option value="drawn" selected>' in row
    token = admin.csrf_token("/admin/robots")
    status, _, _ = admin.request("POST", "/admin/robot-kinds/lab/picture", {"picture": "video", "csrf_token": token})
    assert status == 303
    assert camera_picture(student, "lab-1") == {"kind": "lab", "default": "video", "chosen": None}
    _, _, page = admin.request("GET", "/admin/robots")
    assert "now show the robot&#39;s video" in page or "now show the robot's video" in page


def test_only_admins_choose_and_bad_input_is_refused_with_its_field(client_as, course_people) -> None:
    admin, student, tutor = client_as("admin1"), client_as("student1"), client_as("tutor1")
    for client in (student, tutor):
        assert api(client, "PUT", "/api/admin/robot-kinds/lab/picture", {"picture": "drawn"})[0] == 403
        assert api(client, "GET", "/api/admin/robot-kinds")[0] == 403
    for body, field in (({"picture": "jpeg"}, "picture"), ({"picture": ["drawn"]}, "picture"), ({}, "picture")):
        status, answer = api(admin, "PUT", "/api/admin/robot-kinds/lab/picture", body)
        assert (status, answer["error"]["field"]) == (400, field), answer
    status, answer = api(admin, "PUT", "/api/admin/robot-kinds/no-such-kind/picture", {"picture": "drawn"})
    assert (status, answer["error"]["code"], answer["error"]["field"]) == (404, "unknown_kind", "kind")
    status, answer = api(admin, "PUT", "/api/admin/robot-kinds/bad%20kind/picture", {"picture": "drawn"})
    assert (status, answer["error"]["field"]) == (400, "kind")
    assert camera_picture(student, "lab-1")["default"] == "video"


class RealRobotStandIn(robot_pb2_grpc.RobotServicer):
    """A robot standing for a real one, as the middleware meets it over gRPC: it describes itself but has no scene to
    draw from (GetScene answers UNIMPLEMENTED, as the generated servicer does for what a server leaves out)."""

    def GetRobotInfo(self, request, context):  # noqa: N802 - gRPC's method name
        return robot_pb2.RobotInfo()


@pytest.fixture
def real_robot_address() -> Iterator[str]:
    """A real gRPC server on a free port serving the stand-in."""
    server = grpc.server(ThreadPoolExecutor(max_workers=2))
    robot_pb2_grpc.add_RobotServicer_to_server(RealRobotStandIn(), server)
    port = server.add_insecure_port("127.0.0.1:0")
    server.start()
    try:
        yield f"127.0.0.1:{port}"
    finally:
        server.stop(None)


def kind_picture(admin, kind: str) -> str:
    status, kinds = api(admin, "GET", "/api/admin/robot-kinds")
    assert status == 200, kinds
    return next(entry["camera_picture"] for entry in kinds["kinds"] if entry["kind"] == kind)


def test_drawn_is_refused_for_a_kind_whose_robots_describe_no_scene_naming_the_field(
    client_as, course_people, real_robot_address: str
) -> None:
    admin = client_as("admin1")
    status, answer = api(admin, "POST", "/api/admin/robots",
                         {"name": "real-1", "address": real_robot_address, "kind": "real"})
    assert status == 201, answer

    status, answer = api(admin, "PUT", "/api/admin/robot-kinds/real/picture", {"picture": "drawn"})
    assert (status, answer["error"]["code"], answer["error"]["field"]) == (409, "no_scene", "picture"), answer
    assert "real-1 describes no scene" in answer["error"]["message"]
    assert kind_picture(admin, "real") == "video"
    assert api(admin, "PUT", "/api/admin/robot-kinds/real/picture", {"picture": "video"})[0] == 200

    # Nobody answers for the kind: whether it is simulated cannot be told, so it is refused too, and says why.
    status, answer = api(admin, "PUT", "/api/admin/robot-kinds/ghost/picture", {"picture": "drawn"})
    assert (status, answer["error"]["code"], answer["error"]["field"]) == (409, "scene_unknown", "picture"), answer
    assert "none of its robots answers" in answer["error"]["message"]
    assert kind_picture(admin, "ghost") == "video"

    # The robots page's form says the same sentence and changes nothing.
    token = admin.csrf_token("/admin/robots")
    status, _, _ = admin.request("POST", "/admin/robot-kinds/real/picture", {"picture": "drawn", "csrf_token": token})
    assert status == 303
    _, _, page = admin.request("GET", "/admin/robots")
    assert "real-1 describes no scene to draw from" in page
    assert kind_picture(admin, "real") == "video"
