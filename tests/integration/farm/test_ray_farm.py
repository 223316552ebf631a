"""The Ray farm against a real local Ray cluster: a head and a second worker node, both on 127.0.0.1.

Ray's own `ray.cluster_utils.Cluster` starts the two nodes (separate raylets, one GCS) in this machine;
robots are real skill servers in real actors, and two real web processes share the farm and the database.
"""

from __future__ import annotations

import json
import os
import re
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from benchmarks.ports import free_port
from middleware.farm.ray_farm import prepare_for

prepare_for("127.0.0.1:0")  # before Ray is imported: keep the nodes on loopback

from ray.cluster_utils import Cluster  # noqa: E402

from middleware.farm.base import FarmUnavailable, RobotSpec  # noqa: E402
from middleware.farm.ray_farm import ACTOR_PREFIX, NAMESPACE, RayFarm  # noqa: E402
from middleware.robots.link import CommandRefused, RobotLink  # noqa: E402
from tests.conftest import STUDENT_PASSWORD, LabClient  # noqa: E402


def _print_ray_logs(made: Cluster) -> None:
    """The tails of the raylets' and the GCS's logs, so that a node that did not come up says why in CI's log."""
    logs = Path(made.head_node.get_logs_dir_path())
    for log in sorted(logs.glob("raylet*.out")) + sorted(logs.glob("raylet*.err")) + sorted(logs.glob("gcs_server.*")):
        print(f"--- {log.name} ---", *log.read_text(errors="replace").splitlines()[-25:], sep="\n")


def _two_nodes() -> Cluster:
    """Ray waits a fixed 30 s for a node's raylet to register; on a loaded CI machine it once did not, so a node
    that does not come up is reported with Ray's logs and the whole cluster is started once more. The head too: its
    GCS server once died before it ran (a segmentation fault in the forked child, where Ray's preexec_fn runs Python
    in a copy of the suite's process and its many threads), and Ray waited 60 s for a port it never wrote."""
    for attempt in (1, 2):
        made: Cluster | None = None
        try:
            made = Cluster(initialize_head=True, head_node_args={
                "num_cpus": 2, "node_ip_address": "127.0.0.1", "include_dashboard": False})
            made.add_node(num_cpus=2, node_ip_address="127.0.0.1")
            made.wait_for_nodes()
            return made
        except Exception:
            if made is not None:
                _print_ray_logs(made)
            subprocess.run([sys.executable, "-m", "ray.scripts.scripts", "stop", "--force"], check=False,
                           capture_output=True)
            if attempt == 2:
                raise
    raise AssertionError("unreachable")


@pytest.fixture(scope="module")
def cluster() -> Iterator[Cluster]:
    """A head node and a worker node, each with 2 CPUs, bound to 127.0.0.1."""
    made = _two_nodes()
    yield made
    import ray

    ray.shutdown()
    made.shutdown()


@pytest.fixture
def farm(cluster: Cluster) -> Iterator[RayFarm]:
    made = RayFarm(cluster.address)
    yield made
    for robot in made.robots():
        made.stop(robot.name)


def _drives(address: str, token: str, sequence: int) -> bool:
    link = RobotLink("probe", address, rpc_timeout_s=2.0)
    try:
        return link.drive(token, sequence, 0.1, 0.0).applied_sequence == sequence
    finally:
        link.close()


def test_robots_spread_over_both_nodes_and_obey_only_their_token(farm: RayFarm) -> None:
    with ThreadPoolExecutor(4) as pool:  # started together, as a class's students press "Start"
        robots = list(pool.map(lambda i: farm.start(RobotSpec(f"spread-{i}", "empty", f"token-{i}")), range(4)))
    assert len({robot.node for robot in robots}) == 2
    assert all(robot.host == "127.0.0.1" and robot.address.startswith("127.0.0.1:") for robot in robots)
    assert _drives(robots[0].address, "token-0", 1)
    with pytest.raises(CommandRefused):
        _drives(robots[0].address, "token-1", 2)
    assert farm.start(RobotSpec("spread-0", "empty", "token-0")).address == robots[0].address  # the running one
    capacity = farm.capacity()
    assert capacity.hosts == 2 and capacity.running == 4 and capacity.robots > 4
    assert sorted(robot.name for robot in farm.robots()) == [f"spread-{i}" for i in range(4)]
    assert farm.stop("spread-3") and farm.find("spread-3") is None and not farm.stop("spread-3")
    replaced = farm.start(RobotSpec("spread-2", "empty", "a-new-owner"))  # the old owner lost track of it
    assert _drives(replaced.address, "a-new-owner", 1)
    with pytest.raises(CommandRefused):
        _drives(replaced.address, "token-2", 2)


def test_a_killed_robot_actor_is_restarted_and_obeys_its_controller_again(farm: RayFarm) -> None:
    import ray

    robot = farm.start(RobotSpec("phoenix", "empty", "owner-token"))
    assert _drives(robot.address, "owner-token", 1)
    ray.kill(ray.get_actor(ACTOR_PREFIX + "phoenix", namespace=NAMESPACE), no_restart=False)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        again = farm.find("phoenix")
        if again is not None and again.restarted:
            break
        time.sleep(0.2)
    else:
        pytest.fail("the robot's actor was not restarted within 60 s")
    assert _drives(again.address, "owner-token", 2)
    with pytest.raises(CommandRefused):
        _drives(again.address, "someone-else", 3)


def test_a_fast_robot_is_owned_by_its_process_and_never_restarted(farm: RayFarm) -> None:
    """RobotSpec(fast=True), a plan's prediction: an actor of the process that started it (not detached, so it ends
    with that process; the farm holds its handle meanwhile), whose world runs faster than real time, and which stays
    dead when killed."""
    import ray

    robot = farm.start(RobotSpec("prediction-check", "empty", "owner-token", fast=True))
    time.sleep(1.0)  # Ray ends an actor that is not detached when its last handle goes: the farm holds it
    actor = ray.get_actor(ACTOR_PREFIX + "prediction-check", namespace=NAMESPACE)
    link = RobotLink("probe", robot.address, rpc_timeout_s=5.0)
    stream = link.stream_poses(10.0)
    first = latest = next(iter(stream)).sim_time_s
    began = time.monotonic()
    for message in stream:  # read as they come for a second of wall time
        latest = message.sim_time_s
        if time.monotonic() - began > 1.0:
            break
    stream.cancel()
    link.close()
    assert (latest - first) / (time.monotonic() - began) > 2.0, "the fast robot ran in real time"
    ray.kill(actor, no_restart=False)
    time.sleep(5.0)
    assert farm.find("prediction-check") is None, "a fast robot's actor was restarted"


def test_draining_a_node_moves_its_robots_to_the_other(cluster: Cluster) -> None:
    """Runs on its own node, added and drained here, so the other tests keep both of theirs."""
    spare = cluster.add_node(num_cpus=2, node_ip_address="127.0.0.1", resources={"spare": 1})
    cluster.wait_for_nodes()
    farm = RayFarm(cluster.address)
    try:
        with ThreadPoolExecutor(6) as pool:  # a class pressing "Start" together, as the farm benchmark's does
            robots = list(pool.map(lambda i: farm.start(RobotSpec(f"drain-{i}", "empty", f"token-{i}")), range(6)))
        on_spare = [robot.name for robot in robots if robot.node == spare.node_id]
        assert on_spare, "SPREAD placed no robot on the third node"
        assert sorted(farm.drain(spare.node_id)) == sorted(on_spare)
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            now = {robot.name: robot for robot in farm.robots()}
            if len(now) == 6 and all(robot.node != spare.node_id for robot in now.values()):
                break
            time.sleep(0.3)
        else:
            pytest.fail("the drained node's robots did not move within 60 s")
        assert all(_drives(now[name].address, f"token-{name[-1]}", 1) for name in on_spare)
        with pytest.raises(FarmUnavailable, match="no live node"):
            farm.drain("0" * 56)
    finally:
        for robot in farm.robots():
            farm.stop(robot.name)
        cluster.remove_node(spare)


def test_an_unreachable_farm_is_a_clear_error() -> None:
    with socket.socket() as unused:
        unused.bind(("127.0.0.1", 0))
        port = unused.getsockname()[1]
    with pytest.raises(FarmUnavailable, match=f"127.0.0.1:{port} cannot be reached"):
        RayFarm(f"127.0.0.1:{port}").start(RobotSpec("nowhere", "empty"))


def _web_process(port: int, environment: dict[str, str], log: Path) -> subprocess.Popen[bytes]:
    with log.open("wb") as output:  # the child keeps its own copy of the descriptor
        return subprocess.Popen([sys.executable, "-m", "middleware.cli", "web", "--port", str(port)],
                                env=environment, stdout=output, stderr=subprocess.STDOUT)


def _wait_for(url_client: LabClient, process: subprocess.Popen[bytes], log: Path) -> None:
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        assert process.poll() is None, log.read_text()
        try:
            if url_client.request("GET", "/login")[0] == 200:
                return
        except OSError:
            time.sleep(0.3)
    pytest.fail("a web process did not serve within 60 s:\n" + log.read_text())


def _json(client: LabClient, method: str, path: str, body: object | None = None) -> tuple[int, dict]:
    headers = {"Content-Type": "application/json", "Accept": "application/json",
               "X-CSRFToken": client.csrf_token("/teaching")}
    from urllib.request import Request

    request = Request(client.base_url + path, method=method, headers=headers,
                      data=None if body is None else json.dumps(body).encode())
    try:
        with client._opener.open(request, timeout=120) as response:
            return response.status, json.loads(response.read())
    except Exception as error:  # noqa: BLE001 - 4xx/5xx are answers here
        if not hasattr(error, "code"):
            raise
        return error.code, json.loads(error.read())


def _telelab(environment: dict[str, str], *args: str, code: int = 0) -> str:
    done = subprocess.run([sys.executable, "-m", "middleware.cli", *args], env=environment, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == code, done.stdout + done.stderr
    return done.stdout + done.stderr


def test_two_web_processes_find_and_drive_the_same_farm_robot(cluster: Cluster, tmp_path: Path) -> None:
    from sqlalchemy.orm import sessionmaker

    from middleware.auth.services import create_user
    from middleware.db import make_engine, upgrade_to_head

    database_url = f"sqlite:///{tmp_path / 'lab.sqlite3'}"
    upgrade_to_head(database_url)
    engine = make_engine(database_url)
    with sessionmaker(engine)() as session:
        create_user(session, "student1", "student", STUDENT_PASSWORD)
        session.commit()
    engine.dispose()
    environment = {**os.environ, "TELELAB_DATABASE_URL": database_url, "TELELAB_SECRET_KEY": "same-for-both",
                   "TELELAB_FARM": "ray", "TELELAB_RAY_ADDRESS": cluster.address, "TELELAB_ROBOTS": ""}
    ports = [free_port(), free_port()]
    logs = [tmp_path / f"web-{i}.log" for i in range(2)]
    processes = [_web_process(port, environment, log) for port, log in zip(ports, logs, strict=True)]
    clients = [LabClient(f"http://127.0.0.1:{port}") for port in ports]
    try:
        for client, process, log in zip(clients, processes, logs, strict=True):
            _wait_for(client, process, log)
            assert client.login() == 302
        status, started = _json(clients[0], "POST", "/api/practice")
        assert status == 202 and started["name"] == "practice-student1", started
        status, seen = _json(clients[1], "GET", "/api/practice")
        assert status == 200 and seen["running"] and seen["name"] == "practice-student1"
        for client in clients:
            status, ran = _json(client, "POST", "/api/practice/commands", {"command": {"stop": True}})
            assert status == 202 and ran["robot"] == "practice-student1", ran
        status_report = _telelab(environment, "farm", "status")
        assert "farm: ray, 2 host(s)" in status_report and re.search(r"practice-student1 +student1 +127\.0\.0\.1",
                                                                       status_report), status_report
        assert "stopped practice-student1" in _telelab(environment, "farm", "stop", "practice-student1")
        status, seen = _json(clients[0], "GET", "/api/practice")
        assert status == 200 and not seen["running"]
        assert "no robot called practice-student1" in _telelab(environment, "farm", "stop", "practice-student1",
                                                               code=1)
    finally:
        for process in processes:
            process.terminate()
            process.wait(20)


def test_a_pool_started_from_the_command_line_serves_a_web_process_and_survives_a_killed_actor(
        cluster: Cluster, tmp_path: Path) -> None:
    import ray
    from sqlalchemy import select
    from sqlalchemy.orm import sessionmaker

    from middleware.auth.services import create_user
    from middleware.db import make_engine, upgrade_to_head
    from middleware.models import Robot

    database_url = f"sqlite:///{tmp_path / 'pool.sqlite3'}"
    upgrade_to_head(database_url)
    engine = make_engine(database_url)
    with sessionmaker(engine)() as session:
        create_user(session, "student1", "student", STUDENT_PASSWORD)
        session.commit()
    environment = {**os.environ, "TELELAB_DATABASE_URL": database_url, "TELELAB_SECRET_KEY": "pool",
                   "TELELAB_FARM": "ray", "TELELAB_RAY_ADDRESS": cluster.address, "TELELAB_ROBOTS": ""}
    assert "started raysim-1, raysim-2 (kind raysim, scene empty)" in _telelab(
        environment, "farm", "start", "--pool", "raysim", "--scene", "empty", "--count", "2")
    assert "count must be a whole number" in _telelab(environment, "farm", "start", "--pool", "raysim", "--count",
                                                      "0", code=1)
    port, log = free_port(), tmp_path / "web.log"
    process = _web_process(port, environment, log)
    client = LabClient(f"http://127.0.0.1:{port}")
    try:
        _wait_for(client, process, log)
        assert client.login() == 302
        status, listed = _json(client, "GET", "/api/pools")
        assert {"kind": "raysim", "robots": 2, "online": 2, "free": 2, "queue": 0} in listed["pools"], listed
        status, seat = _json(client, "POST", "/api/pools/raysim/claim")
        assert status == 200 and seat["robot_name"] in ("raysim-1", "raysim-2"), seat
        bound = seat["robot_name"]
        with sessionmaker(engine)() as session:
            before = session.scalar(select(Robot.address).where(Robot.name == bound))
        ray.init(address=cluster.address, namespace=NAMESPACE, ignore_reinit_error=True)
        ray.kill(ray.get_actor(ACTOR_PREFIX + bound, namespace=NAMESPACE), no_restart=False)
        deadline = time.monotonic() + 90
        while True:  # the web process's keeper follows the restarted actor to its new port
            with sessionmaker(engine)() as session:
                after = session.scalar(select(Robot.address).where(Robot.name == bound))
            status, report = _json(client, "GET", f"/api/robots/{bound}")
            if after != before and report.get("online"):
                break
            assert time.monotonic() < deadline, f"{bound} did not serve again: {before} -> {after}\n" + log.read_text()
            time.sleep(0.5)
        assert "stopped raysim-1, raysim-2" in _telelab(environment, "farm", "stop", "--pool", "raysim")
        status, listed = _json(client, "GET", "/api/pools")
        assert all(p["kind"] != "raysim" for p in listed["pools"])
    finally:
        process.terminate()
        process.wait(20)
        engine.dispose()
        RayFarm(cluster.address).stop("raysim-1")
        RayFarm(cluster.address).stop("raysim-2")
