"""Teleperception through the middleware against a real skill server: the evidence grid read by anyone who may
see the robot, its supervisory reset, the raw readings exported as CSV and MCAP (read back with mcap's reader), and
a student's own robot's grid refused to everyone else."""

from __future__ import annotations

import csv
import io
import json
import time
from urllib.request import Request

from mcap.reader import make_reader

from middleware.lab.perception_export import CSV_COLUMNS, MCAP_SCHEMA_NAME, MCAP_TOPIC
from tests.conftest import LabClient
from tests.integration.lab.test_skills_api import api, take_control
from tests.integration.teaching.test_practice_console_and_uploads import _api, _client, practice  # noqa: F401


def wait_for_readings(client: LabClient, at_least: int, robot: str = "lab-1", within_s: float = 20.0) -> dict:
    """Reads the grid (which keeps the robot accumulating) until it holds at_least readings."""
    ends = time.monotonic() + within_s
    while True:
        status, body = api(client, "GET", f"/api/robots/{robot}/evidence")
        assert status == 200, body
        counts = body["evidence"]["counts"]
        if counts["static"] + counts["moving"] >= at_least or time.monotonic() > ends:
            return body["evidence"]
        time.sleep(0.25)


def download(client: LabClient, path: str) -> tuple[int, dict[str, str], bytes]:
    """(status, headers, raw body) of a GET."""
    with client._opener.open(Request(client.base_url + path), timeout=20) as response:
        return response.status, dict(response.headers), response.read()


def test_reading_the_grid_makes_it_accumulate_and_layers_are_chosen_by_name(student_client: LabClient) -> None:
    evidence = wait_for_readings(student_client, 4)
    assert evidence["accumulating"]
    assert evidence["counts"]["sonar"] >= 4 and evidence["counts"]["laser"] >= 4
    grid = evidence["grid"]
    assert grid["width_cells"] > 0 and grid["height_cells"] > 0 and grid["cells_b64"]
    assert set(evidence["odometry"]) == {"x_m", "y_m", "theta_rad"}
    layers = {}
    for sensor in ("sonar", "laser"):
        status, body = api(student_client, "GET", f"/api/robots/lab-1/evidence?sensor={sensor}&part=static")
        assert status == 200, body
        layers[sensor] = body["evidence"]["grid"]["cells_b64"]
    assert layers["sonar"] != layers["laser"], "the sonar ring sees behind the robot, the laser does not"
    for query, field in (("sensor=radar", "sensor"), ("part=later", "part")):
        status, body = api(student_client, "GET", f"/api/robots/lab-1/evidence?{query}")
        assert status == 400 and body["error"]["field"] == field, body


def test_an_observer_sees_the_grid_the_student_gathered(student_client: LabClient, live_server) -> None:
    gathered = wait_for_readings(student_client, 6)
    observer = _client(live_server, "observer1")
    status, body = _api(observer, "GET", "/api/robots/lab-1/evidence")
    assert status == 200, body
    seen = body["evidence"]
    assert sum(seen["counts"][p] for p in ("static", "moving")) >= sum(gathered["counts"][p] for p in ("static",
                                                                                                        "moving"))
    assert seen["version"] >= gathered["version"], "one grid on the robot, not one per viewer"


def test_only_the_controller_may_reset_the_grid_and_then_it_starts_again(student_client: LabClient) -> None:
    wait_for_readings(student_client, 4)
    status, body = api(student_client, "DELETE", "/api/robots/lab-1/evidence")
    assert status == 403 and body["error"]["code"] == "not_controller", body
    counts = wait_for_readings(student_client, 4)["counts"]
    assert counts["static"] + counts["moving"] >= 4, "a refused reset changes nothing"
    queue = take_control(student_client)
    try:
        status, body = api(student_client, "DELETE", "/api/robots/lab-1/evidence")
        assert status == 200, body
        counts = body["evidence"]["counts"]
        assert counts["static"] + counts["moving"] <= 1 and "reset" in body["message"]
    finally:
        queue.close()


def test_a_tutor_may_reset_the_grid_during_a_students_turn(student_client: LabClient, live_server) -> None:
    tutor = _client(live_server, "tutor9", "tutor")
    queue = take_control(student_client)
    try:
        wait_for_readings(student_client, 3)
        status, body = _api(tutor, "DELETE", "/api/robots/lab-1/evidence")
        assert status == 200 and sum(body["evidence"]["counts"][p] for p in ("static", "moving")) <= 1, body
    finally:
        queue.close()


def test_the_readings_export_as_csv_and_as_mcap_that_read_back(student_client: LabClient) -> None:
    wait_for_readings(student_client, 6)
    status, headers, raw_csv = download(student_client, "/api/robots/lab-1/readings.csv")
    assert status == 200 and headers["Content-Type"].startswith("text/csv")
    assert 'filename="teleperception-lab-1.csv"' in headers["Content-Disposition"]
    rows = list(csv.DictReader(io.StringIO(raw_csv.decode())))
    assert tuple(rows[0]) == CSV_COLUMNS
    first_index = rows[0]["scan_index"]
    first_scan = [row for row in rows if row["scan_index"] == first_index]
    assert [row["sensor"] for row in first_scan].count("sonar") == 16
    assert [row["sensor"] for row in first_scan].count("laser") == 181
    assert {row["part"] for row in rows} <= {"static", "moving"}

    status, headers, raw_mcap = download(student_client, "/api/robots/lab-1/readings.mcap")
    assert status == 200 and 'filename="teleperception-lab-1.mcap"' in headers["Content-Disposition"]
    reader = make_reader(io.BytesIO(raw_mcap))
    messages = list(reader.iter_messages(topics=[MCAP_TOPIC]))
    assert len(messages) >= 6
    schema, channel, _ = messages[0]
    assert schema.name == MCAP_SCHEMA_NAME and schema.encoding == "jsonschema" and json.loads(schema.data)
    assert channel.message_encoding == "json" and channel.metadata["pose"] == "odometry"
    by_index = {json.loads(m.data)["scan_index"]: (json.loads(m.data), m.log_time) for _, _, m in messages}
    scan, log_time = by_index[int(first_index)]  # the same reading in both files (the CSV was taken first)
    sonar_rows = [row for row in first_scan if row["sensor"] == "sonar"]
    assert [float(r["range_m"]) for r in sonar_rows] == scan["sonar"]["ranges_m"]
    assert float(first_scan[0]["odom_x_m"]) == round(scan["odometry"]["x_m"], 4)
    assert log_time == int(scan["capture_unix_s"] * 1e9)


def test_a_students_own_robot_grid_is_refused_to_everyone_else(live_server, practice) -> None:  # noqa: F811
    ann, bob = practice
    for path in ("/api/robots/practice-ann/evidence", "/api/robots/practice-ann/readings.csv",
                 "/api/robots/practice-ann/readings.mcap"):
        status, body = _api(bob, "GET", path)
        assert status == 404 and body["error"]["code"] == "unknown_robot", (path, body)
    status, body = _api(bob, "DELETE", "/api/robots/practice-ann/evidence")
    assert status == 404, body
    assert bob.request("GET", "/lab/practice-ann/teleperception")[0] == 404
    status, body = _api(ann, "GET", "/api/robots/practice-ann/evidence")
    assert status == 200 and body["evidence"]["accumulating"], body
    assert ann.request("GET", "/lab/practice-ann/teleperception")[0] == 200


def test_the_export_pages_through_the_robots_readings_until_a_short_page() -> None:
    """A stand-in link (the real robot would need a minute of readings for a second page) answering pages of 600."""
    from middleware.lab import teleperception_routes
    from protos.telelab.v1 import robot_pb2

    class PagedLink:
        def __init__(self, kept: int) -> None:
            self.kept, self.asked = kept, []

        def info(self) -> robot_pb2.RobotInfo:
            return robot_pb2.RobotInfo()

        def perception_readings(self, after_index: int = 0) -> robot_pb2.PerceptionReadings:
            self.asked.append(after_index)
            last = min(self.kept, after_index + teleperception_routes.READINGS_PER_ANSWER)
            return robot_pb2.PerceptionReadings(scans=[robot_pb2.PerceptionScan(index=i)
                                                       for i in range(after_index + 1, last + 1)])

    link = PagedLink(1300)
    scans, _ = teleperception_routes._readings(link)  # type: ignore[arg-type]
    assert [s.index for s in scans] == list(range(1, 1301)) and link.asked == [0, 600, 1200]
    link = PagedLink(1200)
    scans, _ = teleperception_routes._readings(link)  # type: ignore[arg-type]
    assert len(scans) == 1200 and link.asked == [0, 600, 1200]
