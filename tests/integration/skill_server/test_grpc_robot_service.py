"""The Robot service over real gRPC: discovery, control, errors and streams."""

from __future__ import annotations

import math
import threading
import time

import grpc
import pytest
import simplejpeg
from grpc_health.v1 import health_pb2, health_pb2_grpc
from grpc_reflection.v1alpha import reflection_pb2, reflection_pb2_grpc

from protos.telelab.v1 import robot_pb2, robot_pb2_grpc
from skill_server.server import SkillServer, create_server
from skill_server.sim.geometry import Pose2D

DEADLINE_S = 10.0
TOKEN = "integration-token"


@pytest.mark.parametrize("service", ["", "telelab.v1.Robot"])
def test_health_says_serving(channel: grpc.Channel, service: str) -> None:
    response = health_pb2_grpc.HealthStub(channel).Check(
        health_pb2.HealthCheckRequest(service=service), timeout=DEADLINE_S
    )
    assert response.status == health_pb2.HealthCheckResponse.SERVING


def test_reflection_lists_the_robot_service(channel: grpc.Channel) -> None:
    stub = reflection_pb2_grpc.ServerReflectionStub(channel)
    responses = stub.ServerReflectionInfo(
        iter([reflection_pb2.ServerReflectionRequest(list_services="")]), timeout=DEADLINE_S
    )
    names = {service.name for response in responses for service in response.list_services_response.service}
    assert {"telelab.v1.Robot", "grpc.health.v1.Health"} <= names


def test_robot_info_describes_the_robot_and_its_scene(robot: robot_pb2_grpc.RobotStub) -> None:
    info = robot.GetRobotInfo(robot_pb2.GetRobotInfoRequest(), timeout=DEADLINE_S)
    assert (info.robot_name, info.scene_name) == ("lab-1", "lab")
    assert (info.max_linear_mps, info.max_angular_radps, info.deadman_timeout_s) == (0.5, 1.5, 2.0)
    assert (info.camera_width_px, info.camera_height_px, info.camera_hfov_deg) == (320, 240, 60.0)
    assert len(info.sonars) == 16 and info.sonars[0].cone_half_angle_rad > 0
    assert info.laser.beam_count == 181 and info.laser.max_range_m == 8.0
    assert {"wall_east", "pillar"} <= {box.name for box in info.scene_boxes}


def test_list_skills_offers_direct_control_with_its_schema(robot: robot_pb2_grpc.RobotStub) -> None:
    skills = robot.ListSkills(robot_pb2.ListSkillsRequest(), timeout=DEADLINE_S).skills
    direct = next(skill for skill in skills if skill.name == "direct_control")
    linear = next(p for p in direct.parameters if p.name == "linear_mps")
    angular = next(p for p in direct.parameters if p.name == "angular_radps")
    assert (linear.type, linear.unit, linear.minimum, linear.maximum) == (
        robot_pb2.PARAMETER_TYPE_DOUBLE,
        "m/s",
        -0.5,
        0.5,
    )
    assert (angular.unit, angular.maximum, angular.default_value) == ("rad/s", 1.5, 0.0)
    assert linear.help and direct.title


def test_list_skills_publishes_each_skills_declared_traits(robot: robot_pb2_grpc.RobotStub) -> None:
    skills = robot.ListSkills(robot_pb2.ListSkillsRequest(), timeout=DEADLINE_S).skills
    traits = {skill.name: (skill.motor, skill.estimates_pose, skill.direct_drive) for skill in skills}
    assert traits == {
        "direct_control": (True, False, True),
        "go_to_goal": (True, False, False),
        "orientation_control": (True, False, False),
        "wall_following": (True, False, False),
        "round_trip": (True, False, False),
        "detect_obstacle": (False, False, False),
        "environment_modelling": (False, False, False),
        "localization": (False, True, False),
    }


def test_one_drive_command_moves_the_robot_until_the_deadman(fresh_server: SkillServer) -> None:
    with grpc.insecure_channel(fresh_server.address) as channel:
        robot = robot_pb2_grpc.RobotStub(channel)
        telemetry = robot.StreamTelemetry(robot_pb2.StreamTelemetryRequest(rate_hz=50), timeout=DEADLINE_S)
        start = next(telemetry).ground_truth
        robot.SetController(robot_pb2.SetControllerRequest(token=TOKEN), timeout=DEADLINE_S)
        ack = robot.Drive(robot_pb2.DriveCommand(token=TOKEN, sequence=1, linear_mps=0.2), timeout=DEADLINE_S)
        assert (ack.applied_sequence, ack.linear_mps) == (1, 0.2)
        saw_sequence = False
        for message in telemetry:
            saw_sequence |= message.last_applied_sequence == 1
            if message.deadman_stopped and abs(message.odometry.linear_mps) < 0.005:
                break
        telemetry.cancel()
    assert saw_sequence
    # 2 s of deadman at 0.2 m/s; the ramps up and down cancel out.
    assert message.ground_truth.x_m - start.x_m == pytest.approx(0.4, abs=0.04)
    assert message.ground_truth.y_m - start.y_m == pytest.approx(0.0, abs=0.02)


def test_a_pose_only_stream_carries_the_pose_and_nothing_a_student_could_read_the_truth_from(
        robot: robot_pb2_grpc.RobotStub) -> None:
    stream = robot.StreamTelemetry(robot_pb2.StreamTelemetryRequest(rate_hz=30, pose_only=True), timeout=DEADLINE_S)
    messages = [next(stream) for _ in range(3)]
    stream.cancel()
    assert [m.tick for m in messages] == sorted({m.tick for m in messages})
    last = messages[-1]
    assert last.HasField("odometry") and last.capture_unix_s > 0 and last.sim_time_s > 0
    assert not last.HasField("ground_truth") and not last.HasField("laser") and not last.HasField("sonar")
    full = robot.StreamTelemetry(robot_pb2.StreamTelemetryRequest(rate_hz=30), timeout=DEADLINE_S)
    assert last.ByteSize() * 10 < next(full).ByteSize(), "a pose is a small part of the full message"
    full.cancel()


def test_telemetry_messages_advance_and_carry_every_sensor(robot: robot_pb2_grpc.RobotStub) -> None:
    stream = robot.StreamTelemetry(robot_pb2.StreamTelemetryRequest(), timeout=DEADLINE_S)
    messages = [next(stream) for _ in range(5)]
    stream.cancel()
    ticks = [m.tick for m in messages]
    sim_times = [m.sim_time_s for m in messages]
    assert ticks == sorted(set(ticks)) and sim_times == sorted(set(sim_times))
    # The default is 10 Hz of sim time, kept on average: the k-th message is at least k periods after the first. A
    # busy machine may deliver a snapshot late and the next one sooner (the pacer keeps the rate, not each gap).
    assert all(later - sim_times[0] >= k * 0.1 - 1e-9 for k, later in enumerate(sim_times))
    assert [m.capture_unix_s for m in messages] == sorted(m.capture_unix_s for m in messages)
    last = messages[-1]
    assert len(last.sonar.ranges_m) == 16 and len(last.laser.ranges_m) == 181
    assert last.laser.angle_min_rad == pytest.approx(-math.pi / 2)
    assert last.laser.angle_increment_rad == pytest.approx(math.pi / 180)


def test_camera_frames_advance_and_are_320x240_jpegs(robot: robot_pb2_grpc.RobotStub) -> None:
    stream = robot.StreamCamera(robot_pb2.StreamCameraRequest(max_fps=30), timeout=DEADLINE_S)
    frames = [next(stream) for _ in range(4)]
    stream.cancel()
    sequences = [f.frame_sequence for f in frames]
    assert sequences == sorted(set(sequences))
    assert [f.sim_time_s for f in frames] == sorted({f.sim_time_s for f in frames})
    assert [f.capture_unix_s for f in frames] == sorted({f.capture_unix_s for f in frames})
    for frame in frames:
        assert frame.jpeg[:2] == b"\xff\xd8"
        assert (frame.width_px, frame.height_px) == (320, 240)
        assert simplejpeg.decode_jpeg(frame.jpeg).shape == (240, 320, 3)


def test_two_camera_viewers_share_the_same_encoded_frames(robot: robot_pb2_grpc.RobotStub) -> None:
    first = robot.StreamCamera(robot_pb2.StreamCameraRequest(max_fps=30), timeout=DEADLINE_S)
    second = robot.StreamCamera(robot_pb2.StreamCameraRequest(max_fps=30), timeout=DEADLINE_S)
    seen_first = {f.frame_sequence: f.jpeg for f in (next(first) for _ in range(6))}
    seen_second = {f.frame_sequence: f.jpeg for f in (next(second) for _ in range(6))}
    first.cancel()
    second.cancel()
    common = seen_first.keys() & seen_second.keys()
    assert all(seen_first[sequence] == seen_second[sequence] for sequence in common)


def expect_status(call: object, code: grpc.StatusCode, *words: str) -> None:
    """Asserts a unary call's thunk fails with code and details mentioning every word."""
    with pytest.raises(grpc.RpcError) as failed:
        call()
    assert failed.value.code() == code
    for word in words:
        assert word in failed.value.details()


def test_drive_refusals_map_to_status_codes(fresh_server: SkillServer) -> None:
    with grpc.insecure_channel(fresh_server.address) as channel:
        robot = robot_pb2_grpc.RobotStub(channel)
        robot.SetController(robot_pb2.SetControllerRequest(token=TOKEN), timeout=DEADLINE_S)

        def drive(**fields: object) -> robot_pb2.DriveAck:
            return robot.Drive(robot_pb2.DriveCommand(**fields), timeout=DEADLINE_S)

        expect_status(
            lambda: drive(token="stale", sequence=1, linear_mps=0.1),
            grpc.StatusCode.PERMISSION_DENIED,
            "this command's controller token is not the robot's current controller",
        )
        expect_status(lambda: drive(sequence=1, linear_mps=0.1), grpc.StatusCode.UNAUTHENTICATED)
        for linear, angular, field in [
            (math.nan, 0.0, "linear_mps"),
            (0.0, math.inf, "angular_radps"),
            (1e9, 0.0, "linear_mps"),
            (0.0, -2.0, "angular_radps"),
        ]:
            expect_status(
                lambda linear=linear, angular=angular: drive(
                    token=TOKEN, sequence=1, linear_mps=linear, angular_radps=angular
                ),
                grpc.StatusCode.INVALID_ARGUMENT,
                field,
                "between",
            )
        assert drive(token=TOKEN, sequence=1, linear_mps=0.1).applied_sequence == 1
        time.sleep(0.05)
        assert fresh_server.world.snapshot.last_applied_sequence == 1


@pytest.mark.parametrize(
    ("request_stream", "field"),
    [
        (lambda robot: robot.StreamTelemetry(robot_pb2.StreamTelemetryRequest(rate_hz=51)), "rate_hz"),
        (lambda robot: robot.StreamTelemetry(robot_pb2.StreamTelemetryRequest(rate_hz=-1)), "rate_hz"),
        (lambda robot: robot.StreamTelemetry(robot_pb2.StreamTelemetryRequest(rate_hz=math.nan)), "rate_hz"),
        (lambda robot: robot.StreamCamera(robot_pb2.StreamCameraRequest(max_fps=31)), "max_fps"),
        (lambda robot: robot.StreamCamera(robot_pb2.StreamCameraRequest(max_fps=math.inf)), "max_fps"),
    ],
)
def test_out_of_range_stream_rates_are_refused(
    robot: robot_pb2_grpc.RobotStub, request_stream: object, field: str
) -> None:
    expect_status(lambda: next(request_stream(robot)), grpc.StatusCode.INVALID_ARGUMENT, field)


def test_cancelling_a_stream_ends_it_on_both_sides(shared_server: SkillServer, robot: robot_pb2_grpc.RobotStub) -> None:
    stream = robot.StreamCamera(robot_pb2.StreamCameraRequest(), timeout=DEADLINE_S)
    next(stream)
    assert shared_server.world.camera_subscriber_count == 1
    stream.cancel()
    with pytest.raises(grpc.RpcError) as ended:
        next(stream)
    assert ended.value.code() == grpc.StatusCode.CANCELLED
    deadline = time.monotonic() + 5.0
    while shared_server.world.camera_subscriber_count and time.monotonic() < deadline:
        time.sleep(0.01)
    assert shared_server.world.camera_subscriber_count == 0


def test_stopping_the_server_ends_open_streams(fresh_server: SkillServer) -> None:
    with grpc.insecure_channel(fresh_server.address) as channel:
        robot = robot_pb2_grpc.RobotStub(channel)
        telemetry = robot.StreamTelemetry(robot_pb2.StreamTelemetryRequest(), timeout=DEADLINE_S)
        camera = robot.StreamCamera(robot_pb2.StreamCameraRequest(), timeout=DEADLINE_S)
        next(telemetry)
        next(camera)
        stopper = threading.Thread(target=fresh_server.stop, kwargs={"grace_s": 2.0})
        started = time.monotonic()
        stopper.start()
        for stream in (telemetry, camera):
            try:
                for _ in stream:
                    pass
            except grpc.RpcError as error:
                assert error.code() in (grpc.StatusCode.CANCELLED, grpc.StatusCode.UNAVAILABLE)
        stopper.join()
        assert time.monotonic() - started < 3.0
        assert not fresh_server.world.is_running


def test_track_events_stream_as_the_robot_runs_and_a_scene_without_a_track_refuses(
    robot: robot_pb2_grpc.RobotStub,
) -> None:
    expect_status(lambda: next(robot.StreamTrackEvents(robot_pb2.StreamTrackEventsRequest(), timeout=DEADLINE_S)),
                  grpc.StatusCode.FAILED_PRECONDITION, "no track")
    running = create_server(port=0, scene="course-A", realtime=False, robot_name="track-bot")
    try:
        with grpc.insecure_channel(running.address) as channel:
            track = robot_pb2_grpc.RobotStub(channel)
            events = track.StreamTrackEvents(robot_pb2.StreamTrackEventsRequest(after_index=0), timeout=DEADLINE_S)
            running.world.set_pose(Pose2D(-2.0, 0.0, 0.0))  # off A: the run starts
            started = next(events)
            assert (started.index, started.kind, started.attempt) == (1, "started", 1)
            assert track.GetTrackRun(robot_pb2.GetTrackRunRequest(), timeout=DEADLINE_S).phase == "to_b"
            events.cancel()
    finally:
        running.stop(grace_s=0.5)


def test_the_pose_log_gives_the_run_between_two_times_and_refuses_a_backwards_range(
        robot: robot_pb2_grpc.RobotStub) -> None:
    started = time.time()
    time.sleep(1.5)
    log = robot.GetPoseLog(robot_pb2.GetPoseLogRequest(from_unix_s=started, to_unix_s=time.time()), timeout=5)
    assert 0 < log.oldest_unix_s <= started
    times = [sample.unix_s for sample in log.samples]
    assert 4 <= len(times) <= 10 and all(started <= t for t in times)  # 5 Hz, awake or parked (4 Hz)
    assert all(later - earlier <= 0.3 for earlier, later in zip(times, times[1:], strict=False))
    expect_status(lambda: robot.GetPoseLog(robot_pb2.GetPoseLogRequest(from_unix_s=2.0, to_unix_s=1.0), timeout=5),
                  grpc.StatusCode.INVALID_ARGUMENT, "from_unix_s")
