"""The Ray farm: each simulated robot a named, restartable, detached Ray actor in the namespace "telelab".

The actor runs the robot's skill server as its child (the skill server stops when the actor dies) and
reports its address. Any process connected to the cluster finds a robot by name (the named actor), so web
workers on any host reach the same robots. Ray restarts an actor whose process dies, with the same name and
controller token; the new skill server may listen on another host or port, which `find` answers.

Placement declares the resources a headless robot was measured to use (farm/costs.py) and spreads robots
over the nodes, so a cluster of many hosts holds a class.
"""

from __future__ import annotations

import logging
import os
import socket
import threading
from typing import Any, cast

from flask_babel import gettext  # type: ignore[import-untyped]

from middleware.farm.base import Capacity, FarmFull, FarmRobot, FarmUnavailable, RobotSpec
from middleware.farm.costs import RAY_ROBOT_MEMORY_MB, robot_cpu_share, robots_per_host
from middleware.farm.load import CpuMeter, cpu_seconds, resident_mb
from middleware.robots.processes import SkillServerProcess, SkillServerStartError

NAMESPACE = "telelab"
ACTOR_PREFIX = "robot:"
START_TIMEOUT_S = 90.0
CALL_TIMEOUT_S = 20.0
REACH_TIMEOUT_S = 2.0
LOOPBACK_HOSTS = {"127.0.0.1", "localhost", "::1"}
log = logging.getLogger(__name__)


def prepare_for(address: str) -> None:
    """Settings Ray reads when it is imported; call before the first `import ray` of the process.

    Ray on Linux turns a loopback address into the host's network address before connecting; a cluster
    bound to 127.0.0.1 (tests, one-machine labs) is then unreachable. RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER=0
    makes Ray keep 127.0.0.1 as the node's address.
    """
    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
    if address.rsplit(":", 1)[0].strip("[]") in LOOPBACK_HOSTS:
        os.environ.setdefault("RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER", "0")


class RobotActor:
    """One robot in the cluster: its skill server as a child process of the actor, on the node's address."""

    def __init__(self, name: str, scene: str, controller_token: str, fast: bool = False) -> None:
        import ray

        self._restarted = ray.get_runtime_context().was_current_actor_reconstructed
        self._host = ray.util.get_node_ip_address()
        self._node = ray.get_runtime_context().get_node_id()
        self._server = SkillServerProcess(name, scene, restart=False, echo=False, controller_token=controller_token,
                                          host=self._host, exit_with_parent=True, fast=fast)
        self._server.serve()  # SkillServerStartError fails the actor's creation; the farm says so
        self._meter = CpuMeter()
        self._stopping = False
        threading.Thread(target=self._exit_when_the_server_dies, name="robot-watch", daemon=True).start()

    def _exit_when_the_server_dies(self) -> None:
        """A skill server that dies takes its actor down, so Ray restarts both."""
        assert self._server.process is not None
        self._server.process.wait()
        if not self._stopping:
            os._exit(1)

    def describe(self) -> dict[str, Any]:
        """The robot's address, host and load (its skill server and this actor together)."""
        server = self._server.process
        pids = [os.getpid()] + ([server.pid] if server is not None and server.poll() is None else [])
        shares = [self._meter.share(pid) for pid in pids]
        memory = [resident_mb(pid) or 0.0 for pid in pids]
        return {"name": self._server.name, "scene": self._server.scene, "address": self._server.address,
                "host": self._host, "node": self._node, "restarted": self._restarted,
                "cpu_share": None if None in shares else sum(s for s in shares if s is not None),
                "memory_mb": sum(memory), "cpu_s": sum(cpu_seconds(pid) or 0.0 for pid in pids)}

    def obeys(self, controller_token: str) -> bool:
        """Whether the robot was started for this controller token."""
        return self._server.controller_token == controller_token

    def stop(self) -> None:
        """Stops the skill server (the farm then kills the actor without a restart)."""
        self._stopping = True
        self._server.stop()


class RayFarm:
    """Robots as Ray actors on the cluster at address (host:port of its head)."""

    backend = "ray"

    def __init__(self, address: str, cpu_share: float | None = None) -> None:
        self.address = address
        self._cpu_share = robot_cpu_share() if cpu_share is None else cpu_share  # placement declares it
        self._lock = threading.Lock()
        self._connected_pid: int | None = None
        self._actor_class: Any = None
        # The handles of this process's fast robots: Ray ends an actor that is not detached once no handle to it is
        # left, so the farm holds each until stop() (and the process's end ends them all).
        self._owned: dict[str, Any] = {}

    def start(self, spec: RobotSpec) -> FarmRobot:
        ray = self._ray()
        existing = self.find(spec.name)
        if existing is not None:
            actor = ray.get_actor(ACTOR_PREFIX + spec.name, namespace=NAMESPACE)
            if ray.get(actor.obeys.remote(spec.controller_token), timeout=CALL_TIMEOUT_S):
                return existing
            self.stop(spec.name)  # its owner lost track of it (its record was removed): a fresh one replaces it
        capacity = self.capacity()
        if capacity.free <= 0:
            raise FarmFull(gettext("The lab's Ray farm runs as many simulated robots as its %(hosts)s host(s) can "
                                   "(%(robots)s). Try again when a robot is stopped, or add a robot host.",
                                   hosts=capacity.hosts, robots=capacity.robots))
        # A fast robot (a prediction) is owned by this process, not detached: Ray ends it with its owner, and never
        # restarts it. It steps flat out for the seconds a prediction lasts; placement declares the usual share, so a
        # busy node still takes it (a whole core would leave it waiting behind the class's robots).
        actor = self._actor_class.options(
            name=ACTOR_PREFIX + spec.name, namespace=NAMESPACE, lifetime=None if spec.fast else "detached",
            max_restarts=0 if spec.fast else -1, num_cpus=self._cpu_share,
            memory=RAY_ROBOT_MEMORY_MB * 2**20, scheduling_strategy="SPREAD", get_if_exists=True,
        ).remote(spec.name, spec.scene, spec.controller_token, spec.fast)
        try:
            robot = self._robot(ray.get(actor.describe.remote(), timeout=START_TIMEOUT_S))
            if spec.fast:
                self._owned[spec.name] = actor
            return robot
        except Exception as error:  # noqa: BLE001 - Ray raises several kinds; none may leave an actor behind
            ray.kill(actor, no_restart=True)
            log.warning("robot %s did not start on the Ray farm: %s", spec.name, error)
            reason = gettext("its skill server did not start") if _caused_by(error, SkillServerStartError) else \
                gettext("no host took it within %(seconds)s s", seconds=f"{START_TIMEOUT_S:.0f}")
            raise FarmUnavailable(gettext("%(robot)s did not start on the lab's Ray farm: %(reason)s.", robot=spec.name,
                                          reason=reason)) from None

    def find(self, name: str) -> FarmRobot | None:
        ray = self._ray()
        try:
            actor = ray.get_actor(ACTOR_PREFIX + name, namespace=NAMESPACE)
        except ValueError:
            return None
        try:
            return self._robot(ray.get(actor.describe.remote(), timeout=CALL_TIMEOUT_S))
        except ray.exceptions.RayActorError:
            return None  # stopped meanwhile
        except ray.exceptions.GetTimeoutError:
            raise FarmUnavailable(gettext("%(robot)s did not answer the farm within %(seconds)s s; it may be "
                                          "restarting. Try again in a moment.", robot=name,
                                          seconds=f"{CALL_TIMEOUT_S:.0f}")) from None

    def stop(self, name: str) -> bool:
        ray = self._ray()
        try:
            actor = ray.get_actor(ACTOR_PREFIX + name, namespace=NAMESPACE)
        except ValueError:
            self._owned.pop(name, None)
            return False
        try:
            ray.get(actor.stop.remote(), timeout=CALL_TIMEOUT_S)
        except Exception as error:  # noqa: BLE001 - the actor is killed whatever its stop did
            log.info("robot %s did not stop cleanly (%s); killing its actor", name, error.__class__.__name__)
        ray.kill(actor, no_restart=True)
        self._owned.pop(name, None)
        return True

    def robots(self) -> list[FarmRobot]:
        robots = []
        for name in self._names():
            robot = self.find(name)
            if robot is not None:
                robots.append(robot)
        return robots

    def capacity(self) -> Capacity:
        ray = self._ray()
        nodes = [node for node in ray.nodes() if node.get("Alive")]
        # A node's CPUs and "memory" resource are what Ray may give actors already (the operator's and Ray's own
        # reserve are taken out).
        robots = sum(min(robots_per_host(node["Resources"].get("CPU", 0.0), float("inf"), reserve=False,
                                         cpu_share=self._cpu_share),
                         int(node["Resources"].get("memory", 0.0) / 2**20 / RAY_ROBOT_MEMORY_MB)) for node in nodes)
        return Capacity(robots, len(self._names()), hosts=len(nodes))

    def nodes(self) -> list[dict[str, Any]]:
        """The cluster's live nodes: address, CPUs and whether it is the head."""
        return [{"host": node["NodeManagerAddress"], "cpus": node["Resources"].get("CPU", 0.0),
                 "node_id": node["NodeID"]} for node in self._ray().nodes() if node.get("Alive")]

    def drain(self, node: str) -> list[str]:
        """Takes node out of placement and moves its robots to the other nodes (Ray restarts each elsewhere);
        the names of the robots moved. FarmUnavailable when the cluster refuses (an unknown node)."""
        ray = self._ray()
        from ray.core.generated import autoscaler_pb2

        known = {entry["node_id"] for entry in self.nodes()}
        if node not in known:
            raise FarmUnavailable(gettext("The farm has no live node %(node)s; `telelab farm status` lists them.",
                                          node=repr(node)))
        # The GCS call behind Ray's own `ray drain-node`: the node takes no new actors from now on.
        accepted, why = ray._raylet.GcsClient(address=self.address).drain_node(
            node, autoscaler_pb2.DrainNodeReason.Value("DRAIN_NODE_REASON_PREEMPTION"),  # type: ignore[attr-defined]
            "telelab farm drain", 0)
        if not accepted:
            raise FarmUnavailable(gettext("The cluster did not drain %(node)s: %(why)s", node=node, why=why))
        moved = [robot.name for robot in self.robots() if robot.node == node]
        for name in moved:
            ray.kill(ray.get_actor(ACTOR_PREFIX + name, namespace=NAMESPACE), no_restart=False)
        return moved

    def close(self) -> None:
        with self._lock:
            if self._connected_pid == os.getpid():
                import ray

                ray.shutdown()
            self._connected_pid = None

    def _names(self) -> list[str]:
        ray = self._ray()
        return sorted(entry["name"][len(ACTOR_PREFIX):] for entry in ray.util.list_named_actors(all_namespaces=True)
                      if entry["namespace"] == NAMESPACE and entry["name"].startswith(ACTOR_PREFIX))

    def _robot(self, facts: dict[str, Any]) -> FarmRobot:
        return FarmRobot(facts["name"], facts["scene"], facts["address"], facts["host"], self.backend, facts["node"],
                         facts["restarted"], facts["cpu_share"], facts["memory_mb"])

    def _ray(self) -> Any:
        """The ray module, connected to the cluster from this process (once per process: workers fork)."""
        with self._lock:
            if self._connected_pid == os.getpid():
                import ray

                return ray
            _check_reachable(self.address)
            prepare_for(self.address)
            try:
                import ray
            except ImportError:
                raise FarmUnavailable(gettext("This web host has no Ray; install it with pip install "
                                              "'telelab[ray]'.")) from None

            try:
                ray.init(address=self.address, namespace=NAMESPACE, log_to_driver=False,
                         logging_level=logging.WARNING, ignore_reinit_error=True)
            except (ConnectionError, RuntimeError) as error:
                raise FarmUnavailable(gettext("The lab's Ray farm at %(address)s did not accept this process: "
                                              "%(error)s", address=self.address, error=error)) from None
            self._actor_class = ray.remote(RobotActor)
            self._connected_pid = os.getpid()
            return ray


def start_local_cluster() -> str:
    """Starts a one-machine Ray cluster owned by this process, bound to 127.0.0.1; its head's address.

    `telelab up --farm ray` uses it; a lab of several hosts starts its head with `ray start --head` instead.
    """
    prepare_for("127.0.0.1:0")
    import ray

    context = ray.init(_node_ip_address="127.0.0.1", include_dashboard=False, namespace=NAMESPACE,
                       log_to_driver=False, logging_level=logging.WARNING)
    return cast(Any, context).address_info["gcs_address"]  # a RayContext, typed as its base


def _check_reachable(address: str) -> None:
    """A quick TCP look, because Ray itself retries an unreachable head for minutes."""
    host, _, port = address.rpartition(":")
    try:
        with socket.create_connection((host.strip("[]"), int(port)), timeout=REACH_TIMEOUT_S):
            pass
    except (OSError, ValueError):
        raise FarmUnavailable(gettext("The lab's Ray farm at %(address)s cannot be reached. Check that its head runs "
                                      "(`ray start --head`) and TELELAB_RAY_ADDRESS.", address=address)) from None


def _caused_by(error: BaseException, kind: type[BaseException]) -> bool:
    return kind.__name__ in str(error)
