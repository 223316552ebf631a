"""The recording's MCAP channels: each topic and its protobuf message type. The robot's own messages come from the
project's contract (protos/telelab/v1); the command log's type, which no robot RPC carries, is defined here once,
as a protobuf descriptor, so Foxglove decodes every channel from the schema in the file."""

from __future__ import annotations

from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
from google.protobuf.message import Message

from protos.telelab.v1 import robot_pb2

ODOMETRY = "/odometry"
GROUND_TRUTH = "/ground_truth"  # tutors' and graders' only: left out of a student's copy
SONAR = "/sonar"
LASER = "/laser"
LOCALIZATION = "/localization"  # its ground_truth field is cleared in a student's copy
COMMANDS = "/commands"
GOALS = "/goals"
SCENE = "/scene"
ROBOT_INFO = "/robot_info"
CAMERA = "/camera"

TRUTH_TOPICS = frozenset({GROUND_TRUTH})

COMMAND_SOURCES = ("pad", "skill_panel", "cue", "tour_step", "plan", "student_code", "tutor", "api")


def _command_record_type() -> type[Message]:
    file = descriptor_pb2.FileDescriptorProto(name="telelab/recording/v1/command.proto",
                                              package="telelab.recording.v1", syntax="proto3")
    message = file.message_type.add(name="CommandRecord")
    fields = (("sent_unix_s", "DOUBLE"), ("user_id", "UINT64"), ("sequence", "UINT64"), ("source", "STRING"),
              ("action", "STRING"), ("linear_mps", "DOUBLE"), ("angular_radps", "DOUBLE"), ("skill", "STRING"),
              ("parameters_json", "STRING"), ("plan_name", "STRING"), ("accepted", "BOOL"), ("outcome", "STRING"))
    for number, (name, kind) in enumerate(fields, start=1):
        message.field.add(name=name, number=number, type=getattr(descriptor_pb2.FieldDescriptorProto, f"TYPE_{kind}"),
                          label=descriptor_pb2.FieldDescriptorProto.LABEL_OPTIONAL)
    pool = descriptor_pool.DescriptorPool()
    pool.Add(file)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName("telelab.recording.v1.CommandRecord"))


CommandRecord = _command_record_type()

MESSAGE_TYPES: dict[str, type[Message]] = {
    ODOMETRY: robot_pb2.Odometry, GROUND_TRUTH: robot_pb2.Pose2D, SONAR: robot_pb2.SonarReading,
    LASER: robot_pb2.LaserScan, LOCALIZATION: robot_pb2.LocalizationUpdate, COMMANDS: CommandRecord,
    GOALS: robot_pb2.GoalState, SCENE: robot_pb2.SceneDescription, ROBOT_INFO: robot_pb2.RobotInfo,
    CAMERA: robot_pb2.CameraFrame,
}
