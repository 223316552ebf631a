from google.protobuf.internal import containers as _containers
from google.protobuf.internal import enum_type_wrapper as _enum_type_wrapper
from google.protobuf import descriptor as _descriptor
from google.protobuf import message as _message
from collections.abc import Iterable as _Iterable, Mapping as _Mapping
from typing import ClassVar as _ClassVar, Optional as _Optional, Union as _Union

DESCRIPTOR: _descriptor.FileDescriptor

class ConsoleView(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = ()
    CONSOLE_VIEW_UNSPECIFIED: _ClassVar[ConsoleView]
    CONSOLE_VIEW_DRIVE: _ClassVar[ConsoleView]
    CONSOLE_VIEW_NAVIGATE: _ClassVar[ConsoleView]
    CONSOLE_VIEW_SENSE: _ClassVar[ConsoleView]
    CONSOLE_VIEW_CHAT: _ClassVar[ConsoleView]

class RobotStream(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = ()
    ROBOT_STREAM_UNSPECIFIED: _ClassVar[RobotStream]
    ROBOT_STREAM_CAMERA: _ClassVar[RobotStream]
    ROBOT_STREAM_TELEMETRY: _ClassVar[RobotStream]
    ROBOT_STREAM_LOCALIZATION: _ClassVar[RobotStream]

class SkillClass(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = ()
    SKILL_CLASS_UNSPECIFIED: _ClassVar[SkillClass]
    SKILL_CLASS_MOTOR: _ClassVar[SkillClass]
    SKILL_CLASS_PERCEPTIVE: _ClassVar[SkillClass]
    SKILL_CLASS_SENSORIMOTOR: _ClassVar[SkillClass]
    SKILL_CLASS_DELIBERATIVE: _ClassVar[SkillClass]

class ParameterType(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = ()
    PARAMETER_TYPE_UNSPECIFIED: _ClassVar[ParameterType]
    PARAMETER_TYPE_DOUBLE: _ClassVar[ParameterType]
    PARAMETER_TYPE_INT: _ClassVar[ParameterType]
    PARAMETER_TYPE_BOOL: _ClassVar[ParameterType]
    PARAMETER_TYPE_ENUM: _ClassVar[ParameterType]

class GoalStatus(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = ()
    GOAL_STATUS_UNSPECIFIED: _ClassVar[GoalStatus]
    GOAL_STATUS_ACCEPTED: _ClassVar[GoalStatus]
    GOAL_STATUS_EXECUTING: _ClassVar[GoalStatus]
    GOAL_STATUS_CANCELING: _ClassVar[GoalStatus]
    GOAL_STATUS_SUCCEEDED: _ClassVar[GoalStatus]
    GOAL_STATUS_CANCELED: _ClassVar[GoalStatus]
    GOAL_STATUS_ABORTED: _ClassVar[GoalStatus]

class GoalEventKind(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = ()
    GOAL_EVENT_KIND_UNSPECIFIED: _ClassVar[GoalEventKind]
    GOAL_EVENT_KIND_STARTED: _ClassVar[GoalEventKind]
    GOAL_EVENT_KIND_STEP_STARTED: _ClassVar[GoalEventKind]
    GOAL_EVENT_KIND_OBSTACLE_DETECTED: _ClassVar[GoalEventKind]
    GOAL_EVENT_KIND_PATH_REPLANNED: _ClassVar[GoalEventKind]
    GOAL_EVENT_KIND_CONVERGED: _ClassVar[GoalEventKind]
    GOAL_EVENT_KIND_GOAL_REACHED: _ClassVar[GoalEventKind]
    GOAL_EVENT_KIND_FAILED: _ClassVar[GoalEventKind]
    GOAL_EVENT_KIND_CANCELED: _ClassVar[GoalEventKind]
    GOAL_EVENT_KIND_PREEMPTED: _ClassVar[GoalEventKind]
    GOAL_EVENT_KIND_WALL_LOST: _ClassVar[GoalEventKind]
    GOAL_EVENT_KIND_BATTERY_LOW: _ClassVar[GoalEventKind]
    GOAL_EVENT_KIND_HANDLED: _ClassVar[GoalEventKind]

class FloorPatchKind(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = ()
    FLOOR_PATCH_KIND_UNSPECIFIED: _ClassVar[FloorPatchKind]
    FLOOR_PATCH_KIND_FLOOR: _ClassVar[FloorPatchKind]
    FLOOR_PATCH_KIND_PAINT: _ClassVar[FloorPatchKind]
    FLOOR_PATCH_KIND_GRID: _ClassVar[FloorPatchKind]
    FLOOR_PATCH_KIND_TRACK_LINE: _ClassVar[FloorPatchKind]
    FLOOR_PATCH_KIND_TRACK_POINT: _ClassVar[FloorPatchKind]

class PartShape(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = ()
    PART_SHAPE_UNSPECIFIED: _ClassVar[PartShape]
    PART_SHAPE_BOX: _ClassVar[PartShape]
    PART_SHAPE_CYLINDER: _ClassVar[PartShape]
    PART_SHAPE_SPHERE: _ClassVar[PartShape]

class EvidenceSensor(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = ()
    EVIDENCE_SENSOR_UNSPECIFIED: _ClassVar[EvidenceSensor]
    EVIDENCE_SENSOR_SONAR: _ClassVar[EvidenceSensor]
    EVIDENCE_SENSOR_LASER: _ClassVar[EvidenceSensor]

class EvidencePart(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = ()
    EVIDENCE_PART_UNSPECIFIED: _ClassVar[EvidencePart]
    EVIDENCE_PART_STATIC: _ClassVar[EvidencePart]
    EVIDENCE_PART_MOVING: _ClassVar[EvidencePart]
CONSOLE_VIEW_UNSPECIFIED: ConsoleView
CONSOLE_VIEW_DRIVE: ConsoleView
CONSOLE_VIEW_NAVIGATE: ConsoleView
CONSOLE_VIEW_SENSE: ConsoleView
CONSOLE_VIEW_CHAT: ConsoleView
ROBOT_STREAM_UNSPECIFIED: RobotStream
ROBOT_STREAM_CAMERA: RobotStream
ROBOT_STREAM_TELEMETRY: RobotStream
ROBOT_STREAM_LOCALIZATION: RobotStream
SKILL_CLASS_UNSPECIFIED: SkillClass
SKILL_CLASS_MOTOR: SkillClass
SKILL_CLASS_PERCEPTIVE: SkillClass
SKILL_CLASS_SENSORIMOTOR: SkillClass
SKILL_CLASS_DELIBERATIVE: SkillClass
PARAMETER_TYPE_UNSPECIFIED: ParameterType
PARAMETER_TYPE_DOUBLE: ParameterType
PARAMETER_TYPE_INT: ParameterType
PARAMETER_TYPE_BOOL: ParameterType
PARAMETER_TYPE_ENUM: ParameterType
GOAL_STATUS_UNSPECIFIED: GoalStatus
GOAL_STATUS_ACCEPTED: GoalStatus
GOAL_STATUS_EXECUTING: GoalStatus
GOAL_STATUS_CANCELING: GoalStatus
GOAL_STATUS_SUCCEEDED: GoalStatus
GOAL_STATUS_CANCELED: GoalStatus
GOAL_STATUS_ABORTED: GoalStatus
GOAL_EVENT_KIND_UNSPECIFIED: GoalEventKind
GOAL_EVENT_KIND_STARTED: GoalEventKind
GOAL_EVENT_KIND_STEP_STARTED: GoalEventKind
GOAL_EVENT_KIND_OBSTACLE_DETECTED: GoalEventKind
GOAL_EVENT_KIND_PATH_REPLANNED: GoalEventKind
GOAL_EVENT_KIND_CONVERGED: GoalEventKind
GOAL_EVENT_KIND_GOAL_REACHED: GoalEventKind
GOAL_EVENT_KIND_FAILED: GoalEventKind
GOAL_EVENT_KIND_CANCELED: GoalEventKind
GOAL_EVENT_KIND_PREEMPTED: GoalEventKind
GOAL_EVENT_KIND_WALL_LOST: GoalEventKind
GOAL_EVENT_KIND_BATTERY_LOW: GoalEventKind
GOAL_EVENT_KIND_HANDLED: GoalEventKind
FLOOR_PATCH_KIND_UNSPECIFIED: FloorPatchKind
FLOOR_PATCH_KIND_FLOOR: FloorPatchKind
FLOOR_PATCH_KIND_PAINT: FloorPatchKind
FLOOR_PATCH_KIND_GRID: FloorPatchKind
FLOOR_PATCH_KIND_TRACK_LINE: FloorPatchKind
FLOOR_PATCH_KIND_TRACK_POINT: FloorPatchKind
PART_SHAPE_UNSPECIFIED: PartShape
PART_SHAPE_BOX: PartShape
PART_SHAPE_CYLINDER: PartShape
PART_SHAPE_SPHERE: PartShape
EVIDENCE_SENSOR_UNSPECIFIED: EvidenceSensor
EVIDENCE_SENSOR_SONAR: EvidenceSensor
EVIDENCE_SENSOR_LASER: EvidenceSensor
EVIDENCE_PART_UNSPECIFIED: EvidencePart
EVIDENCE_PART_STATIC: EvidencePart
EVIDENCE_PART_MOVING: EvidencePart

class GetRobotInfoRequest(_message.Message):
    __slots__ = ()
    def __init__(self) -> None: ...

class RobotInfo(_message.Message):
    __slots__ = ("robot_name", "scene_name", "wheel_base_m", "wheel_radius_m", "body_radius_m", "max_linear_mps", "max_angular_radps", "deadman_timeout_s", "camera_hfov_deg", "camera_width_px", "camera_height_px", "sonars", "laser", "scene_boxes", "panels", "line_sensor")
    ROBOT_NAME_FIELD_NUMBER: _ClassVar[int]
    SCENE_NAME_FIELD_NUMBER: _ClassVar[int]
    WHEEL_BASE_M_FIELD_NUMBER: _ClassVar[int]
    WHEEL_RADIUS_M_FIELD_NUMBER: _ClassVar[int]
    BODY_RADIUS_M_FIELD_NUMBER: _ClassVar[int]
    MAX_LINEAR_MPS_FIELD_NUMBER: _ClassVar[int]
    MAX_ANGULAR_RADPS_FIELD_NUMBER: _ClassVar[int]
    DEADMAN_TIMEOUT_S_FIELD_NUMBER: _ClassVar[int]
    CAMERA_HFOV_DEG_FIELD_NUMBER: _ClassVar[int]
    CAMERA_WIDTH_PX_FIELD_NUMBER: _ClassVar[int]
    CAMERA_HEIGHT_PX_FIELD_NUMBER: _ClassVar[int]
    SONARS_FIELD_NUMBER: _ClassVar[int]
    LASER_FIELD_NUMBER: _ClassVar[int]
    SCENE_BOXES_FIELD_NUMBER: _ClassVar[int]
    PANELS_FIELD_NUMBER: _ClassVar[int]
    LINE_SENSOR_FIELD_NUMBER: _ClassVar[int]
    robot_name: str
    scene_name: str
    wheel_base_m: float
    wheel_radius_m: float
    body_radius_m: float
    max_linear_mps: float
    max_angular_radps: float
    deadman_timeout_s: float
    camera_hfov_deg: float
    camera_width_px: int
    camera_height_px: int
    sonars: _containers.RepeatedCompositeFieldContainer[SonarGeometry]
    laser: LaserGeometry
    scene_boxes: _containers.RepeatedCompositeFieldContainer[SceneBox]
    panels: _containers.RepeatedCompositeFieldContainer[PanelDescription]
    line_sensor: LineSensorGeometry
    def __init__(self, robot_name: _Optional[str] = ..., scene_name: _Optional[str] = ..., wheel_base_m: _Optional[float] = ..., wheel_radius_m: _Optional[float] = ..., body_radius_m: _Optional[float] = ..., max_linear_mps: _Optional[float] = ..., max_angular_radps: _Optional[float] = ..., deadman_timeout_s: _Optional[float] = ..., camera_hfov_deg: _Optional[float] = ..., camera_width_px: _Optional[int] = ..., camera_height_px: _Optional[int] = ..., sonars: _Optional[_Iterable[_Union[SonarGeometry, _Mapping]]] = ..., laser: _Optional[_Union[LaserGeometry, _Mapping]] = ..., scene_boxes: _Optional[_Iterable[_Union[SceneBox, _Mapping]]] = ..., panels: _Optional[_Iterable[_Union[PanelDescription, _Mapping]]] = ..., line_sensor: _Optional[_Union[LineSensorGeometry, _Mapping]] = ...) -> None: ...

class LineSensorGeometry(_message.Message):
    __slots__ = ("ahead_m", "offsets_m")
    AHEAD_M_FIELD_NUMBER: _ClassVar[int]
    OFFSETS_M_FIELD_NUMBER: _ClassVar[int]
    ahead_m: float
    offsets_m: _containers.RepeatedScalarFieldContainer[float]
    def __init__(self, ahead_m: _Optional[float] = ..., offsets_m: _Optional[_Iterable[float]] = ...) -> None: ...

class PanelDescription(_message.Message):
    __slots__ = ("id", "kind", "title", "help", "view", "stream")
    ID_FIELD_NUMBER: _ClassVar[int]
    KIND_FIELD_NUMBER: _ClassVar[int]
    TITLE_FIELD_NUMBER: _ClassVar[int]
    HELP_FIELD_NUMBER: _ClassVar[int]
    VIEW_FIELD_NUMBER: _ClassVar[int]
    STREAM_FIELD_NUMBER: _ClassVar[int]
    id: str
    kind: str
    title: str
    help: str
    view: ConsoleView
    stream: RobotStream
    def __init__(self, id: _Optional[str] = ..., kind: _Optional[str] = ..., title: _Optional[str] = ..., help: _Optional[str] = ..., view: _Optional[_Union[ConsoleView, str]] = ..., stream: _Optional[_Union[RobotStream, str]] = ...) -> None: ...

class SonarGeometry(_message.Message):
    __slots__ = ("mount_angle_rad", "cone_half_angle_rad", "min_range_m", "max_range_m")
    MOUNT_ANGLE_RAD_FIELD_NUMBER: _ClassVar[int]
    CONE_HALF_ANGLE_RAD_FIELD_NUMBER: _ClassVar[int]
    MIN_RANGE_M_FIELD_NUMBER: _ClassVar[int]
    MAX_RANGE_M_FIELD_NUMBER: _ClassVar[int]
    mount_angle_rad: float
    cone_half_angle_rad: float
    min_range_m: float
    max_range_m: float
    def __init__(self, mount_angle_rad: _Optional[float] = ..., cone_half_angle_rad: _Optional[float] = ..., min_range_m: _Optional[float] = ..., max_range_m: _Optional[float] = ...) -> None: ...

class LaserGeometry(_message.Message):
    __slots__ = ("angle_min_rad", "angle_max_rad", "beam_count", "min_range_m", "max_range_m", "height_m")
    ANGLE_MIN_RAD_FIELD_NUMBER: _ClassVar[int]
    ANGLE_MAX_RAD_FIELD_NUMBER: _ClassVar[int]
    BEAM_COUNT_FIELD_NUMBER: _ClassVar[int]
    MIN_RANGE_M_FIELD_NUMBER: _ClassVar[int]
    MAX_RANGE_M_FIELD_NUMBER: _ClassVar[int]
    HEIGHT_M_FIELD_NUMBER: _ClassVar[int]
    angle_min_rad: float
    angle_max_rad: float
    beam_count: int
    min_range_m: float
    max_range_m: float
    height_m: float
    def __init__(self, angle_min_rad: _Optional[float] = ..., angle_max_rad: _Optional[float] = ..., beam_count: _Optional[int] = ..., min_range_m: _Optional[float] = ..., max_range_m: _Optional[float] = ..., height_m: _Optional[float] = ...) -> None: ...

class SceneBox(_message.Message):
    __slots__ = ("name", "center_x_m", "center_y_m", "half_x_m", "half_y_m", "yaw_rad")
    NAME_FIELD_NUMBER: _ClassVar[int]
    CENTER_X_M_FIELD_NUMBER: _ClassVar[int]
    CENTER_Y_M_FIELD_NUMBER: _ClassVar[int]
    HALF_X_M_FIELD_NUMBER: _ClassVar[int]
    HALF_Y_M_FIELD_NUMBER: _ClassVar[int]
    YAW_RAD_FIELD_NUMBER: _ClassVar[int]
    name: str
    center_x_m: float
    center_y_m: float
    half_x_m: float
    half_y_m: float
    yaw_rad: float
    def __init__(self, name: _Optional[str] = ..., center_x_m: _Optional[float] = ..., center_y_m: _Optional[float] = ..., half_x_m: _Optional[float] = ..., half_y_m: _Optional[float] = ..., yaw_rad: _Optional[float] = ...) -> None: ...

class ListSkillsRequest(_message.Message):
    __slots__ = ()
    def __init__(self) -> None: ...

class ListSkillsResponse(_message.Message):
    __slots__ = ("skills",)
    SKILLS_FIELD_NUMBER: _ClassVar[int]
    skills: _containers.RepeatedCompositeFieldContainer[SkillDescription]
    def __init__(self, skills: _Optional[_Iterable[_Union[SkillDescription, _Mapping]]] = ...) -> None: ...

class SkillDescription(_message.Message):
    __slots__ = ("name", "title", "help", "parameters", "motor", "estimates_pose", "direct_drive", "skill_class")
    NAME_FIELD_NUMBER: _ClassVar[int]
    TITLE_FIELD_NUMBER: _ClassVar[int]
    HELP_FIELD_NUMBER: _ClassVar[int]
    PARAMETERS_FIELD_NUMBER: _ClassVar[int]
    MOTOR_FIELD_NUMBER: _ClassVar[int]
    ESTIMATES_POSE_FIELD_NUMBER: _ClassVar[int]
    DIRECT_DRIVE_FIELD_NUMBER: _ClassVar[int]
    SKILL_CLASS_FIELD_NUMBER: _ClassVar[int]
    name: str
    title: str
    help: str
    parameters: _containers.RepeatedCompositeFieldContainer[ParameterSchema]
    motor: bool
    estimates_pose: bool
    direct_drive: bool
    skill_class: SkillClass
    def __init__(self, name: _Optional[str] = ..., title: _Optional[str] = ..., help: _Optional[str] = ..., parameters: _Optional[_Iterable[_Union[ParameterSchema, _Mapping]]] = ..., motor: _Optional[bool] = ..., estimates_pose: _Optional[bool] = ..., direct_drive: _Optional[bool] = ..., skill_class: _Optional[_Union[SkillClass, str]] = ...) -> None: ...

class ParameterSchema(_message.Message):
    __slots__ = ("name", "type", "unit", "minimum", "maximum", "default_value", "help", "choices")
    NAME_FIELD_NUMBER: _ClassVar[int]
    TYPE_FIELD_NUMBER: _ClassVar[int]
    UNIT_FIELD_NUMBER: _ClassVar[int]
    MINIMUM_FIELD_NUMBER: _ClassVar[int]
    MAXIMUM_FIELD_NUMBER: _ClassVar[int]
    DEFAULT_VALUE_FIELD_NUMBER: _ClassVar[int]
    HELP_FIELD_NUMBER: _ClassVar[int]
    CHOICES_FIELD_NUMBER: _ClassVar[int]
    name: str
    type: ParameterType
    unit: str
    minimum: float
    maximum: float
    default_value: float
    help: str
    choices: _containers.RepeatedScalarFieldContainer[str]
    def __init__(self, name: _Optional[str] = ..., type: _Optional[_Union[ParameterType, str]] = ..., unit: _Optional[str] = ..., minimum: _Optional[float] = ..., maximum: _Optional[float] = ..., default_value: _Optional[float] = ..., help: _Optional[str] = ..., choices: _Optional[_Iterable[str]] = ...) -> None: ...

class SetControllerRequest(_message.Message):
    __slots__ = ("token",)
    TOKEN_FIELD_NUMBER: _ClassVar[int]
    token: str
    def __init__(self, token: _Optional[str] = ...) -> None: ...

class SetControllerResponse(_message.Message):
    __slots__ = ()
    def __init__(self) -> None: ...

class DriveCommand(_message.Message):
    __slots__ = ("token", "sequence", "linear_mps", "angular_radps")
    TOKEN_FIELD_NUMBER: _ClassVar[int]
    SEQUENCE_FIELD_NUMBER: _ClassVar[int]
    LINEAR_MPS_FIELD_NUMBER: _ClassVar[int]
    ANGULAR_RADPS_FIELD_NUMBER: _ClassVar[int]
    token: str
    sequence: int
    linear_mps: float
    angular_radps: float
    def __init__(self, token: _Optional[str] = ..., sequence: _Optional[int] = ..., linear_mps: _Optional[float] = ..., angular_radps: _Optional[float] = ...) -> None: ...

class DriveAck(_message.Message):
    __slots__ = ("applied_sequence", "linear_mps", "angular_radps")
    APPLIED_SEQUENCE_FIELD_NUMBER: _ClassVar[int]
    LINEAR_MPS_FIELD_NUMBER: _ClassVar[int]
    ANGULAR_RADPS_FIELD_NUMBER: _ClassVar[int]
    applied_sequence: int
    linear_mps: float
    angular_radps: float
    def __init__(self, applied_sequence: _Optional[int] = ..., linear_mps: _Optional[float] = ..., angular_radps: _Optional[float] = ...) -> None: ...

class DriveStreamAck(_message.Message):
    __slots__ = ("sequence", "ack", "refusal")
    SEQUENCE_FIELD_NUMBER: _ClassVar[int]
    ACK_FIELD_NUMBER: _ClassVar[int]
    REFUSAL_FIELD_NUMBER: _ClassVar[int]
    sequence: int
    ack: DriveAck
    refusal: CommandRefusal
    def __init__(self, sequence: _Optional[int] = ..., ack: _Optional[_Union[DriveAck, _Mapping]] = ..., refusal: _Optional[_Union[CommandRefusal, _Mapping]] = ...) -> None: ...

class CommandRefusal(_message.Message):
    __slots__ = ("status_code", "message", "field")
    STATUS_CODE_FIELD_NUMBER: _ClassVar[int]
    MESSAGE_FIELD_NUMBER: _ClassVar[int]
    FIELD_FIELD_NUMBER: _ClassVar[int]
    status_code: int
    message: str
    field: str
    def __init__(self, status_code: _Optional[int] = ..., message: _Optional[str] = ..., field: _Optional[str] = ...) -> None: ...

class StreamTelemetryRequest(_message.Message):
    __slots__ = ("rate_hz", "pose_only")
    RATE_HZ_FIELD_NUMBER: _ClassVar[int]
    POSE_ONLY_FIELD_NUMBER: _ClassVar[int]
    rate_hz: float
    pose_only: bool
    def __init__(self, rate_hz: _Optional[float] = ..., pose_only: _Optional[bool] = ...) -> None: ...

class Pose2D(_message.Message):
    __slots__ = ("x_m", "y_m", "theta_rad")
    X_M_FIELD_NUMBER: _ClassVar[int]
    Y_M_FIELD_NUMBER: _ClassVar[int]
    THETA_RAD_FIELD_NUMBER: _ClassVar[int]
    x_m: float
    y_m: float
    theta_rad: float
    def __init__(self, x_m: _Optional[float] = ..., y_m: _Optional[float] = ..., theta_rad: _Optional[float] = ...) -> None: ...

class Odometry(_message.Message):
    __slots__ = ("pose", "linear_mps", "angular_radps")
    POSE_FIELD_NUMBER: _ClassVar[int]
    LINEAR_MPS_FIELD_NUMBER: _ClassVar[int]
    ANGULAR_RADPS_FIELD_NUMBER: _ClassVar[int]
    pose: Pose2D
    linear_mps: float
    angular_radps: float
    def __init__(self, pose: _Optional[_Union[Pose2D, _Mapping]] = ..., linear_mps: _Optional[float] = ..., angular_radps: _Optional[float] = ...) -> None: ...

class SonarReading(_message.Message):
    __slots__ = ("ranges_m",)
    RANGES_M_FIELD_NUMBER: _ClassVar[int]
    ranges_m: _containers.RepeatedScalarFieldContainer[float]
    def __init__(self, ranges_m: _Optional[_Iterable[float]] = ...) -> None: ...

class LaserScan(_message.Message):
    __slots__ = ("angle_min_rad", "angle_increment_rad", "ranges_m")
    ANGLE_MIN_RAD_FIELD_NUMBER: _ClassVar[int]
    ANGLE_INCREMENT_RAD_FIELD_NUMBER: _ClassVar[int]
    RANGES_M_FIELD_NUMBER: _ClassVar[int]
    angle_min_rad: float
    angle_increment_rad: float
    ranges_m: _containers.RepeatedScalarFieldContainer[float]
    def __init__(self, angle_min_rad: _Optional[float] = ..., angle_increment_rad: _Optional[float] = ..., ranges_m: _Optional[_Iterable[float]] = ...) -> None: ...

class Telemetry(_message.Message):
    __slots__ = ("tick", "sim_time_s", "capture_unix_s", "last_applied_sequence", "odometry", "ground_truth", "sonar", "laser", "deadman_stopped", "battery", "line")
    TICK_FIELD_NUMBER: _ClassVar[int]
    SIM_TIME_S_FIELD_NUMBER: _ClassVar[int]
    CAPTURE_UNIX_S_FIELD_NUMBER: _ClassVar[int]
    LAST_APPLIED_SEQUENCE_FIELD_NUMBER: _ClassVar[int]
    ODOMETRY_FIELD_NUMBER: _ClassVar[int]
    GROUND_TRUTH_FIELD_NUMBER: _ClassVar[int]
    SONAR_FIELD_NUMBER: _ClassVar[int]
    LASER_FIELD_NUMBER: _ClassVar[int]
    DEADMAN_STOPPED_FIELD_NUMBER: _ClassVar[int]
    BATTERY_FIELD_NUMBER: _ClassVar[int]
    LINE_FIELD_NUMBER: _ClassVar[int]
    tick: int
    sim_time_s: float
    capture_unix_s: float
    last_applied_sequence: int
    odometry: Odometry
    ground_truth: Pose2D
    sonar: SonarReading
    laser: LaserScan
    deadman_stopped: bool
    battery: Battery
    line: LineSensorReading
    def __init__(self, tick: _Optional[int] = ..., sim_time_s: _Optional[float] = ..., capture_unix_s: _Optional[float] = ..., last_applied_sequence: _Optional[int] = ..., odometry: _Optional[_Union[Odometry, _Mapping]] = ..., ground_truth: _Optional[_Union[Pose2D, _Mapping]] = ..., sonar: _Optional[_Union[SonarReading, _Mapping]] = ..., laser: _Optional[_Union[LaserScan, _Mapping]] = ..., deadman_stopped: _Optional[bool] = ..., battery: _Optional[_Union[Battery, _Mapping]] = ..., line: _Optional[_Union[LineSensorReading, _Mapping]] = ...) -> None: ...

class LineSensorReading(_message.Message):
    __slots__ = ("values",)
    VALUES_FIELD_NUMBER: _ClassVar[int]
    values: _containers.RepeatedScalarFieldContainer[float]
    def __init__(self, values: _Optional[_Iterable[float]] = ...) -> None: ...

class Battery(_message.Message):
    __slots__ = ("charge", "charging", "empty")
    CHARGE_FIELD_NUMBER: _ClassVar[int]
    CHARGING_FIELD_NUMBER: _ClassVar[int]
    EMPTY_FIELD_NUMBER: _ClassVar[int]
    charge: float
    charging: bool
    empty: bool
    def __init__(self, charge: _Optional[float] = ..., charging: _Optional[bool] = ..., empty: _Optional[bool] = ...) -> None: ...

class StreamCameraRequest(_message.Message):
    __slots__ = ("max_fps",)
    MAX_FPS_FIELD_NUMBER: _ClassVar[int]
    max_fps: float
    def __init__(self, max_fps: _Optional[float] = ...) -> None: ...

class CameraFrame(_message.Message):
    __slots__ = ("frame_sequence", "capture_unix_s", "sim_time_s", "last_applied_sequence", "pose_at_capture", "width_px", "height_px", "jpeg")
    FRAME_SEQUENCE_FIELD_NUMBER: _ClassVar[int]
    CAPTURE_UNIX_S_FIELD_NUMBER: _ClassVar[int]
    SIM_TIME_S_FIELD_NUMBER: _ClassVar[int]
    LAST_APPLIED_SEQUENCE_FIELD_NUMBER: _ClassVar[int]
    POSE_AT_CAPTURE_FIELD_NUMBER: _ClassVar[int]
    WIDTH_PX_FIELD_NUMBER: _ClassVar[int]
    HEIGHT_PX_FIELD_NUMBER: _ClassVar[int]
    JPEG_FIELD_NUMBER: _ClassVar[int]
    frame_sequence: int
    capture_unix_s: float
    sim_time_s: float
    last_applied_sequence: int
    pose_at_capture: Pose2D
    width_px: int
    height_px: int
    jpeg: bytes
    def __init__(self, frame_sequence: _Optional[int] = ..., capture_unix_s: _Optional[float] = ..., sim_time_s: _Optional[float] = ..., last_applied_sequence: _Optional[int] = ..., pose_at_capture: _Optional[_Union[Pose2D, _Mapping]] = ..., width_px: _Optional[int] = ..., height_px: _Optional[int] = ..., jpeg: _Optional[bytes] = ...) -> None: ...

class ParameterValue(_message.Message):
    __slots__ = ("double_value", "int_value", "bool_value", "string_value")
    DOUBLE_VALUE_FIELD_NUMBER: _ClassVar[int]
    INT_VALUE_FIELD_NUMBER: _ClassVar[int]
    BOOL_VALUE_FIELD_NUMBER: _ClassVar[int]
    STRING_VALUE_FIELD_NUMBER: _ClassVar[int]
    double_value: float
    int_value: int
    bool_value: bool
    string_value: str
    def __init__(self, double_value: _Optional[float] = ..., int_value: _Optional[int] = ..., bool_value: _Optional[bool] = ..., string_value: _Optional[str] = ...) -> None: ...

class ActivateSkillRequest(_message.Message):
    __slots__ = ("token", "skill", "parameters", "preempt")
    class ParametersEntry(_message.Message):
        __slots__ = ("key", "value")
        KEY_FIELD_NUMBER: _ClassVar[int]
        VALUE_FIELD_NUMBER: _ClassVar[int]
        key: str
        value: ParameterValue
        def __init__(self, key: _Optional[str] = ..., value: _Optional[_Union[ParameterValue, _Mapping]] = ...) -> None: ...
    TOKEN_FIELD_NUMBER: _ClassVar[int]
    SKILL_FIELD_NUMBER: _ClassVar[int]
    PARAMETERS_FIELD_NUMBER: _ClassVar[int]
    PREEMPT_FIELD_NUMBER: _ClassVar[int]
    token: str
    skill: str
    parameters: _containers.MessageMap[str, ParameterValue]
    preempt: bool
    def __init__(self, token: _Optional[str] = ..., skill: _Optional[str] = ..., parameters: _Optional[_Mapping[str, ParameterValue]] = ..., preempt: _Optional[bool] = ...) -> None: ...

class ActivateSkillResponse(_message.Message):
    __slots__ = ("goal", "preempted_goal_id")
    GOAL_FIELD_NUMBER: _ClassVar[int]
    PREEMPTED_GOAL_ID_FIELD_NUMBER: _ClassVar[int]
    goal: GoalState
    preempted_goal_id: str
    def __init__(self, goal: _Optional[_Union[GoalState, _Mapping]] = ..., preempted_goal_id: _Optional[str] = ...) -> None: ...

class GoalFeedback(_message.Message):
    __slots__ = ("sim_time_s", "state", "progress", "distance_error_m", "heading_error_rad", "pose", "pose_source", "values", "planned_path")
    class ValuesEntry(_message.Message):
        __slots__ = ("key", "value")
        KEY_FIELD_NUMBER: _ClassVar[int]
        VALUE_FIELD_NUMBER: _ClassVar[int]
        key: str
        value: float
        def __init__(self, key: _Optional[str] = ..., value: _Optional[float] = ...) -> None: ...
    SIM_TIME_S_FIELD_NUMBER: _ClassVar[int]
    STATE_FIELD_NUMBER: _ClassVar[int]
    PROGRESS_FIELD_NUMBER: _ClassVar[int]
    DISTANCE_ERROR_M_FIELD_NUMBER: _ClassVar[int]
    HEADING_ERROR_RAD_FIELD_NUMBER: _ClassVar[int]
    POSE_FIELD_NUMBER: _ClassVar[int]
    POSE_SOURCE_FIELD_NUMBER: _ClassVar[int]
    VALUES_FIELD_NUMBER: _ClassVar[int]
    PLANNED_PATH_FIELD_NUMBER: _ClassVar[int]
    sim_time_s: float
    state: str
    progress: float
    distance_error_m: float
    heading_error_rad: float
    pose: Pose2D
    pose_source: str
    values: _containers.ScalarMap[str, float]
    planned_path: _containers.RepeatedCompositeFieldContainer[Pose2D]
    def __init__(self, sim_time_s: _Optional[float] = ..., state: _Optional[str] = ..., progress: _Optional[float] = ..., distance_error_m: _Optional[float] = ..., heading_error_rad: _Optional[float] = ..., pose: _Optional[_Union[Pose2D, _Mapping]] = ..., pose_source: _Optional[str] = ..., values: _Optional[_Mapping[str, float]] = ..., planned_path: _Optional[_Iterable[_Union[Pose2D, _Mapping]]] = ...) -> None: ...

class GoalEvent(_message.Message):
    __slots__ = ("index", "sim_time_s", "kind", "message")
    INDEX_FIELD_NUMBER: _ClassVar[int]
    SIM_TIME_S_FIELD_NUMBER: _ClassVar[int]
    KIND_FIELD_NUMBER: _ClassVar[int]
    MESSAGE_FIELD_NUMBER: _ClassVar[int]
    index: int
    sim_time_s: float
    kind: GoalEventKind
    message: str
    def __init__(self, index: _Optional[int] = ..., sim_time_s: _Optional[float] = ..., kind: _Optional[_Union[GoalEventKind, str]] = ..., message: _Optional[str] = ...) -> None: ...

class GoalState(_message.Message):
    __slots__ = ("goal_id", "skill", "motor", "status", "parameters", "accepted_sim_s", "ended_sim_s", "error_code", "message", "feedback", "goal_reached")
    class ParametersEntry(_message.Message):
        __slots__ = ("key", "value")
        KEY_FIELD_NUMBER: _ClassVar[int]
        VALUE_FIELD_NUMBER: _ClassVar[int]
        key: str
        value: ParameterValue
        def __init__(self, key: _Optional[str] = ..., value: _Optional[_Union[ParameterValue, _Mapping]] = ...) -> None: ...
    GOAL_ID_FIELD_NUMBER: _ClassVar[int]
    SKILL_FIELD_NUMBER: _ClassVar[int]
    MOTOR_FIELD_NUMBER: _ClassVar[int]
    STATUS_FIELD_NUMBER: _ClassVar[int]
    PARAMETERS_FIELD_NUMBER: _ClassVar[int]
    ACCEPTED_SIM_S_FIELD_NUMBER: _ClassVar[int]
    ENDED_SIM_S_FIELD_NUMBER: _ClassVar[int]
    ERROR_CODE_FIELD_NUMBER: _ClassVar[int]
    MESSAGE_FIELD_NUMBER: _ClassVar[int]
    FEEDBACK_FIELD_NUMBER: _ClassVar[int]
    GOAL_REACHED_FIELD_NUMBER: _ClassVar[int]
    goal_id: str
    skill: str
    motor: bool
    status: GoalStatus
    parameters: _containers.MessageMap[str, ParameterValue]
    accepted_sim_s: float
    ended_sim_s: float
    error_code: str
    message: str
    feedback: GoalFeedback
    goal_reached: bool
    def __init__(self, goal_id: _Optional[str] = ..., skill: _Optional[str] = ..., motor: _Optional[bool] = ..., status: _Optional[_Union[GoalStatus, str]] = ..., parameters: _Optional[_Mapping[str, ParameterValue]] = ..., accepted_sim_s: _Optional[float] = ..., ended_sim_s: _Optional[float] = ..., error_code: _Optional[str] = ..., message: _Optional[str] = ..., feedback: _Optional[_Union[GoalFeedback, _Mapping]] = ..., goal_reached: _Optional[bool] = ...) -> None: ...

class CancelGoalRequest(_message.Message):
    __slots__ = ("token", "goal_id")
    TOKEN_FIELD_NUMBER: _ClassVar[int]
    GOAL_ID_FIELD_NUMBER: _ClassVar[int]
    token: str
    goal_id: str
    def __init__(self, token: _Optional[str] = ..., goal_id: _Optional[str] = ...) -> None: ...

class GetGoalRequest(_message.Message):
    __slots__ = ("goal_id",)
    GOAL_ID_FIELD_NUMBER: _ClassVar[int]
    goal_id: str
    def __init__(self, goal_id: _Optional[str] = ...) -> None: ...

class ListGoalsRequest(_message.Message):
    __slots__ = ()
    def __init__(self) -> None: ...

class ListGoalsResponse(_message.Message):
    __slots__ = ("goals",)
    GOALS_FIELD_NUMBER: _ClassVar[int]
    goals: _containers.RepeatedCompositeFieldContainer[GoalState]
    def __init__(self, goals: _Optional[_Iterable[_Union[GoalState, _Mapping]]] = ...) -> None: ...

class WatchGoalRequest(_message.Message):
    __slots__ = ("goal_id", "feedback_rate_hz")
    GOAL_ID_FIELD_NUMBER: _ClassVar[int]
    FEEDBACK_RATE_HZ_FIELD_NUMBER: _ClassVar[int]
    goal_id: str
    feedback_rate_hz: float
    def __init__(self, goal_id: _Optional[str] = ..., feedback_rate_hz: _Optional[float] = ...) -> None: ...

class GoalUpdate(_message.Message):
    __slots__ = ("event", "feedback", "state")
    EVENT_FIELD_NUMBER: _ClassVar[int]
    FEEDBACK_FIELD_NUMBER: _ClassVar[int]
    STATE_FIELD_NUMBER: _ClassVar[int]
    event: GoalEvent
    feedback: GoalFeedback
    state: GoalState
    def __init__(self, event: _Optional[_Union[GoalEvent, _Mapping]] = ..., feedback: _Optional[_Union[GoalFeedback, _Mapping]] = ..., state: _Optional[_Union[GoalState, _Mapping]] = ...) -> None: ...

class GetMapRequest(_message.Message):
    __slots__ = ()
    def __init__(self) -> None: ...

class ClearMapRequest(_message.Message):
    __slots__ = ("token",)
    TOKEN_FIELD_NUMBER: _ClassVar[int]
    token: str
    def __init__(self, token: _Optional[str] = ...) -> None: ...

class ClearMapResponse(_message.Message):
    __slots__ = ("ended_goal_ids",)
    ENDED_GOAL_IDS_FIELD_NUMBER: _ClassVar[int]
    ended_goal_ids: _containers.RepeatedScalarFieldContainer[str]
    def __init__(self, ended_goal_ids: _Optional[_Iterable[str]] = ...) -> None: ...

class ReturnToDockRequest(_message.Message):
    __slots__ = ("token",)
    TOKEN_FIELD_NUMBER: _ClassVar[int]
    token: str
    def __init__(self, token: _Optional[str] = ...) -> None: ...

class GetHealthRequest(_message.Message):
    __slots__ = ()
    def __init__(self) -> None: ...

class RobotFault(_message.Message):
    __slots__ = ("unix_s", "kind", "message")
    UNIX_S_FIELD_NUMBER: _ClassVar[int]
    KIND_FIELD_NUMBER: _ClassVar[int]
    MESSAGE_FIELD_NUMBER: _ClassVar[int]
    unix_s: float
    kind: str
    message: str
    def __init__(self, unix_s: _Optional[float] = ..., kind: _Optional[str] = ..., message: _Optional[str] = ...) -> None: ...

class RobotHealth(_message.Message):
    __slots__ = ("real_time_factor", "loop_lag_ms_p50", "loop_lag_ms_max", "parked", "cpu_percent", "rss_bytes", "uptime_s", "version", "pid", "faults", "log_tail", "restartable", "restarts")
    REAL_TIME_FACTOR_FIELD_NUMBER: _ClassVar[int]
    LOOP_LAG_MS_P50_FIELD_NUMBER: _ClassVar[int]
    LOOP_LAG_MS_MAX_FIELD_NUMBER: _ClassVar[int]
    PARKED_FIELD_NUMBER: _ClassVar[int]
    CPU_PERCENT_FIELD_NUMBER: _ClassVar[int]
    RSS_BYTES_FIELD_NUMBER: _ClassVar[int]
    UPTIME_S_FIELD_NUMBER: _ClassVar[int]
    VERSION_FIELD_NUMBER: _ClassVar[int]
    PID_FIELD_NUMBER: _ClassVar[int]
    FAULTS_FIELD_NUMBER: _ClassVar[int]
    LOG_TAIL_FIELD_NUMBER: _ClassVar[int]
    RESTARTABLE_FIELD_NUMBER: _ClassVar[int]
    RESTARTS_FIELD_NUMBER: _ClassVar[int]
    real_time_factor: float
    loop_lag_ms_p50: float
    loop_lag_ms_max: float
    parked: bool
    cpu_percent: float
    rss_bytes: int
    uptime_s: float
    version: str
    pid: int
    faults: _containers.RepeatedCompositeFieldContainer[RobotFault]
    log_tail: _containers.RepeatedScalarFieldContainer[str]
    restartable: bool
    restarts: int
    def __init__(self, real_time_factor: _Optional[float] = ..., loop_lag_ms_p50: _Optional[float] = ..., loop_lag_ms_max: _Optional[float] = ..., parked: _Optional[bool] = ..., cpu_percent: _Optional[float] = ..., rss_bytes: _Optional[int] = ..., uptime_s: _Optional[float] = ..., version: _Optional[str] = ..., pid: _Optional[int] = ..., faults: _Optional[_Iterable[_Union[RobotFault, _Mapping]]] = ..., log_tail: _Optional[_Iterable[str]] = ..., restartable: _Optional[bool] = ..., restarts: _Optional[int] = ...) -> None: ...

class RestartRequest(_message.Message):
    __slots__ = ("token",)
    TOKEN_FIELD_NUMBER: _ClassVar[int]
    token: str
    def __init__(self, token: _Optional[str] = ...) -> None: ...

class RestartResponse(_message.Message):
    __slots__ = ("restarting", "message")
    RESTARTING_FIELD_NUMBER: _ClassVar[int]
    MESSAGE_FIELD_NUMBER: _ClassVar[int]
    restarting: bool
    message: str
    def __init__(self, restarting: _Optional[bool] = ..., message: _Optional[str] = ...) -> None: ...

class ReturnToDockResponse(_message.Message):
    __slots__ = ("ended_goal_ids", "dock")
    ENDED_GOAL_IDS_FIELD_NUMBER: _ClassVar[int]
    DOCK_FIELD_NUMBER: _ClassVar[int]
    ended_goal_ids: _containers.RepeatedScalarFieldContainer[str]
    dock: Pose2D
    def __init__(self, ended_goal_ids: _Optional[_Iterable[str]] = ..., dock: _Optional[_Union[Pose2D, _Mapping]] = ...) -> None: ...

class PlaceRobotRequest(_message.Message):
    __slots__ = ("token", "pose", "kidnap")
    TOKEN_FIELD_NUMBER: _ClassVar[int]
    POSE_FIELD_NUMBER: _ClassVar[int]
    KIDNAP_FIELD_NUMBER: _ClassVar[int]
    token: str
    pose: Pose2D
    kidnap: bool
    def __init__(self, token: _Optional[str] = ..., pose: _Optional[_Union[Pose2D, _Mapping]] = ..., kidnap: _Optional[bool] = ...) -> None: ...

class PlaceRobotResponse(_message.Message):
    __slots__ = ("ended_goal_ids", "pose")
    ENDED_GOAL_IDS_FIELD_NUMBER: _ClassVar[int]
    POSE_FIELD_NUMBER: _ClassVar[int]
    ended_goal_ids: _containers.RepeatedScalarFieldContainer[str]
    pose: Pose2D
    def __init__(self, ended_goal_ids: _Optional[_Iterable[str]] = ..., pose: _Optional[_Union[Pose2D, _Mapping]] = ...) -> None: ...

class OccupancyGrid(_message.Message):
    __slots__ = ("resolution_m", "origin_x_m", "origin_y_m", "width_cells", "height_cells", "cells", "scans_integrated", "sim_time_s")
    RESOLUTION_M_FIELD_NUMBER: _ClassVar[int]
    ORIGIN_X_M_FIELD_NUMBER: _ClassVar[int]
    ORIGIN_Y_M_FIELD_NUMBER: _ClassVar[int]
    WIDTH_CELLS_FIELD_NUMBER: _ClassVar[int]
    HEIGHT_CELLS_FIELD_NUMBER: _ClassVar[int]
    CELLS_FIELD_NUMBER: _ClassVar[int]
    SCANS_INTEGRATED_FIELD_NUMBER: _ClassVar[int]
    SIM_TIME_S_FIELD_NUMBER: _ClassVar[int]
    resolution_m: float
    origin_x_m: float
    origin_y_m: float
    width_cells: int
    height_cells: int
    cells: bytes
    scans_integrated: int
    sim_time_s: float
    def __init__(self, resolution_m: _Optional[float] = ..., origin_x_m: _Optional[float] = ..., origin_y_m: _Optional[float] = ..., width_cells: _Optional[int] = ..., height_cells: _Optional[int] = ..., cells: _Optional[bytes] = ..., scans_integrated: _Optional[int] = ..., sim_time_s: _Optional[float] = ...) -> None: ...

class StreamLocalizationRequest(_message.Message):
    __slots__ = ("rate_hz", "max_particles")
    RATE_HZ_FIELD_NUMBER: _ClassVar[int]
    MAX_PARTICLES_FIELD_NUMBER: _ClassVar[int]
    rate_hz: float
    max_particles: int
    def __init__(self, rate_hz: _Optional[float] = ..., max_particles: _Optional[int] = ...) -> None: ...

class Particle(_message.Message):
    __slots__ = ("x_m", "y_m", "theta_rad", "weight")
    X_M_FIELD_NUMBER: _ClassVar[int]
    Y_M_FIELD_NUMBER: _ClassVar[int]
    THETA_RAD_FIELD_NUMBER: _ClassVar[int]
    WEIGHT_FIELD_NUMBER: _ClassVar[int]
    x_m: float
    y_m: float
    theta_rad: float
    weight: float
    def __init__(self, x_m: _Optional[float] = ..., y_m: _Optional[float] = ..., theta_rad: _Optional[float] = ..., weight: _Optional[float] = ...) -> None: ...

class LocalizationUpdate(_message.Message):
    __slots__ = ("sim_time_s", "active", "converged", "estimate", "std_x_m", "std_y_m", "std_theta_rad", "odometry", "ground_truth", "position_error_m", "heading_error_rad", "odometry_position_error_m", "odometry_heading_error_rad", "update_duration_ms", "particles", "navigation_pose", "navigation_source")
    SIM_TIME_S_FIELD_NUMBER: _ClassVar[int]
    ACTIVE_FIELD_NUMBER: _ClassVar[int]
    CONVERGED_FIELD_NUMBER: _ClassVar[int]
    ESTIMATE_FIELD_NUMBER: _ClassVar[int]
    STD_X_M_FIELD_NUMBER: _ClassVar[int]
    STD_Y_M_FIELD_NUMBER: _ClassVar[int]
    STD_THETA_RAD_FIELD_NUMBER: _ClassVar[int]
    ODOMETRY_FIELD_NUMBER: _ClassVar[int]
    GROUND_TRUTH_FIELD_NUMBER: _ClassVar[int]
    POSITION_ERROR_M_FIELD_NUMBER: _ClassVar[int]
    HEADING_ERROR_RAD_FIELD_NUMBER: _ClassVar[int]
    ODOMETRY_POSITION_ERROR_M_FIELD_NUMBER: _ClassVar[int]
    ODOMETRY_HEADING_ERROR_RAD_FIELD_NUMBER: _ClassVar[int]
    UPDATE_DURATION_MS_FIELD_NUMBER: _ClassVar[int]
    PARTICLES_FIELD_NUMBER: _ClassVar[int]
    NAVIGATION_POSE_FIELD_NUMBER: _ClassVar[int]
    NAVIGATION_SOURCE_FIELD_NUMBER: _ClassVar[int]
    sim_time_s: float
    active: bool
    converged: bool
    estimate: Pose2D
    std_x_m: float
    std_y_m: float
    std_theta_rad: float
    odometry: Pose2D
    ground_truth: Pose2D
    position_error_m: float
    heading_error_rad: float
    odometry_position_error_m: float
    odometry_heading_error_rad: float
    update_duration_ms: float
    particles: _containers.RepeatedCompositeFieldContainer[Particle]
    navigation_pose: Pose2D
    navigation_source: str
    def __init__(self, sim_time_s: _Optional[float] = ..., active: _Optional[bool] = ..., converged: _Optional[bool] = ..., estimate: _Optional[_Union[Pose2D, _Mapping]] = ..., std_x_m: _Optional[float] = ..., std_y_m: _Optional[float] = ..., std_theta_rad: _Optional[float] = ..., odometry: _Optional[_Union[Pose2D, _Mapping]] = ..., ground_truth: _Optional[_Union[Pose2D, _Mapping]] = ..., position_error_m: _Optional[float] = ..., heading_error_rad: _Optional[float] = ..., odometry_position_error_m: _Optional[float] = ..., odometry_heading_error_rad: _Optional[float] = ..., update_duration_ms: _Optional[float] = ..., particles: _Optional[_Iterable[_Union[Particle, _Mapping]]] = ..., navigation_pose: _Optional[_Union[Pose2D, _Mapping]] = ..., navigation_source: _Optional[str] = ...) -> None: ...

class GetTrackRunRequest(_message.Message):
    __slots__ = ()
    def __init__(self) -> None: ...

class TrackRun(_message.Message):
    __slots__ = ("is_track", "scene_name", "phase", "attempt", "elapsed_s", "errors", "last_attempt", "last_total_time_s", "last_errors", "last_finished_unix_s", "started_unix_s", "last_started_unix_s")
    IS_TRACK_FIELD_NUMBER: _ClassVar[int]
    SCENE_NAME_FIELD_NUMBER: _ClassVar[int]
    PHASE_FIELD_NUMBER: _ClassVar[int]
    ATTEMPT_FIELD_NUMBER: _ClassVar[int]
    ELAPSED_S_FIELD_NUMBER: _ClassVar[int]
    ERRORS_FIELD_NUMBER: _ClassVar[int]
    LAST_ATTEMPT_FIELD_NUMBER: _ClassVar[int]
    LAST_TOTAL_TIME_S_FIELD_NUMBER: _ClassVar[int]
    LAST_ERRORS_FIELD_NUMBER: _ClassVar[int]
    LAST_FINISHED_UNIX_S_FIELD_NUMBER: _ClassVar[int]
    STARTED_UNIX_S_FIELD_NUMBER: _ClassVar[int]
    LAST_STARTED_UNIX_S_FIELD_NUMBER: _ClassVar[int]
    is_track: bool
    scene_name: str
    phase: str
    attempt: int
    elapsed_s: float
    errors: int
    last_attempt: int
    last_total_time_s: float
    last_errors: int
    last_finished_unix_s: float
    started_unix_s: float
    last_started_unix_s: float
    def __init__(self, is_track: _Optional[bool] = ..., scene_name: _Optional[str] = ..., phase: _Optional[str] = ..., attempt: _Optional[int] = ..., elapsed_s: _Optional[float] = ..., errors: _Optional[int] = ..., last_attempt: _Optional[int] = ..., last_total_time_s: _Optional[float] = ..., last_errors: _Optional[int] = ..., last_finished_unix_s: _Optional[float] = ..., started_unix_s: _Optional[float] = ..., last_started_unix_s: _Optional[float] = ...) -> None: ...

class RestartTrackRunRequest(_message.Message):
    __slots__ = ()
    def __init__(self) -> None: ...

class StreamTrackEventsRequest(_message.Message):
    __slots__ = ("after_index",)
    AFTER_INDEX_FIELD_NUMBER: _ClassVar[int]
    after_index: int
    def __init__(self, after_index: _Optional[int] = ...) -> None: ...

class TrackEvent(_message.Message):
    __slots__ = ("index", "kind", "sim_time_s", "unix_s", "attempt", "elapsed_s", "errors", "message")
    INDEX_FIELD_NUMBER: _ClassVar[int]
    KIND_FIELD_NUMBER: _ClassVar[int]
    SIM_TIME_S_FIELD_NUMBER: _ClassVar[int]
    UNIX_S_FIELD_NUMBER: _ClassVar[int]
    ATTEMPT_FIELD_NUMBER: _ClassVar[int]
    ELAPSED_S_FIELD_NUMBER: _ClassVar[int]
    ERRORS_FIELD_NUMBER: _ClassVar[int]
    MESSAGE_FIELD_NUMBER: _ClassVar[int]
    index: int
    kind: str
    sim_time_s: float
    unix_s: float
    attempt: int
    elapsed_s: float
    errors: int
    message: str
    def __init__(self, index: _Optional[int] = ..., kind: _Optional[str] = ..., sim_time_s: _Optional[float] = ..., unix_s: _Optional[float] = ..., attempt: _Optional[int] = ..., elapsed_s: _Optional[float] = ..., errors: _Optional[int] = ..., message: _Optional[str] = ...) -> None: ...

class GetPoseLogRequest(_message.Message):
    __slots__ = ("from_unix_s", "to_unix_s")
    FROM_UNIX_S_FIELD_NUMBER: _ClassVar[int]
    TO_UNIX_S_FIELD_NUMBER: _ClassVar[int]
    from_unix_s: float
    to_unix_s: float
    def __init__(self, from_unix_s: _Optional[float] = ..., to_unix_s: _Optional[float] = ...) -> None: ...

class PoseSample(_message.Message):
    __slots__ = ("unix_s", "ground_truth", "odometry")
    UNIX_S_FIELD_NUMBER: _ClassVar[int]
    GROUND_TRUTH_FIELD_NUMBER: _ClassVar[int]
    ODOMETRY_FIELD_NUMBER: _ClassVar[int]
    unix_s: float
    ground_truth: Pose2D
    odometry: Pose2D
    def __init__(self, unix_s: _Optional[float] = ..., ground_truth: _Optional[_Union[Pose2D, _Mapping]] = ..., odometry: _Optional[_Union[Pose2D, _Mapping]] = ...) -> None: ...

class PoseLog(_message.Message):
    __slots__ = ("samples", "oldest_unix_s")
    SAMPLES_FIELD_NUMBER: _ClassVar[int]
    OLDEST_UNIX_S_FIELD_NUMBER: _ClassVar[int]
    samples: _containers.RepeatedCompositeFieldContainer[PoseSample]
    oldest_unix_s: float
    def __init__(self, samples: _Optional[_Iterable[_Union[PoseSample, _Mapping]]] = ..., oldest_unix_s: _Optional[float] = ...) -> None: ...

class GetSceneRequest(_message.Message):
    __slots__ = ("known_version",)
    KNOWN_VERSION_FIELD_NUMBER: _ClassVar[int]
    known_version: str
    def __init__(self, known_version: _Optional[str] = ...) -> None: ...

class Rgba(_message.Message):
    __slots__ = ("r", "g", "b", "a")
    R_FIELD_NUMBER: _ClassVar[int]
    G_FIELD_NUMBER: _ClassVar[int]
    B_FIELD_NUMBER: _ClassVar[int]
    A_FIELD_NUMBER: _ClassVar[int]
    r: float
    g: float
    b: float
    a: float
    def __init__(self, r: _Optional[float] = ..., g: _Optional[float] = ..., b: _Optional[float] = ..., a: _Optional[float] = ...) -> None: ...

class Vector3(_message.Message):
    __slots__ = ("x", "y", "z")
    X_FIELD_NUMBER: _ClassVar[int]
    Y_FIELD_NUMBER: _ClassVar[int]
    Z_FIELD_NUMBER: _ClassVar[int]
    x: float
    y: float
    z: float
    def __init__(self, x: _Optional[float] = ..., y: _Optional[float] = ..., z: _Optional[float] = ...) -> None: ...

class Quaternion(_message.Message):
    __slots__ = ("x", "y", "z", "w")
    X_FIELD_NUMBER: _ClassVar[int]
    Y_FIELD_NUMBER: _ClassVar[int]
    Z_FIELD_NUMBER: _ClassVar[int]
    W_FIELD_NUMBER: _ClassVar[int]
    x: float
    y: float
    z: float
    w: float
    def __init__(self, x: _Optional[float] = ..., y: _Optional[float] = ..., z: _Optional[float] = ..., w: _Optional[float] = ...) -> None: ...

class FloorPatch(_message.Message):
    __slots__ = ("center_x_m", "center_y_m", "half_x_m", "half_y_m", "top_z_m", "colour", "kind")
    CENTER_X_M_FIELD_NUMBER: _ClassVar[int]
    CENTER_Y_M_FIELD_NUMBER: _ClassVar[int]
    HALF_X_M_FIELD_NUMBER: _ClassVar[int]
    HALF_Y_M_FIELD_NUMBER: _ClassVar[int]
    TOP_Z_M_FIELD_NUMBER: _ClassVar[int]
    COLOUR_FIELD_NUMBER: _ClassVar[int]
    KIND_FIELD_NUMBER: _ClassVar[int]
    center_x_m: float
    center_y_m: float
    half_x_m: float
    half_y_m: float
    top_z_m: float
    colour: Rgba
    kind: FloorPatchKind
    def __init__(self, center_x_m: _Optional[float] = ..., center_y_m: _Optional[float] = ..., half_x_m: _Optional[float] = ..., half_y_m: _Optional[float] = ..., top_z_m: _Optional[float] = ..., colour: _Optional[_Union[Rgba, _Mapping]] = ..., kind: _Optional[_Union[FloorPatchKind, str]] = ...) -> None: ...

class SceneBlock(_message.Message):
    __slots__ = ("name", "center_x_m", "center_y_m", "half_x_m", "half_y_m", "height_m", "yaw_rad", "colour")
    NAME_FIELD_NUMBER: _ClassVar[int]
    CENTER_X_M_FIELD_NUMBER: _ClassVar[int]
    CENTER_Y_M_FIELD_NUMBER: _ClassVar[int]
    HALF_X_M_FIELD_NUMBER: _ClassVar[int]
    HALF_Y_M_FIELD_NUMBER: _ClassVar[int]
    HEIGHT_M_FIELD_NUMBER: _ClassVar[int]
    YAW_RAD_FIELD_NUMBER: _ClassVar[int]
    COLOUR_FIELD_NUMBER: _ClassVar[int]
    name: str
    center_x_m: float
    center_y_m: float
    half_x_m: float
    half_y_m: float
    height_m: float
    yaw_rad: float
    colour: Rgba
    def __init__(self, name: _Optional[str] = ..., center_x_m: _Optional[float] = ..., center_y_m: _Optional[float] = ..., half_x_m: _Optional[float] = ..., half_y_m: _Optional[float] = ..., height_m: _Optional[float] = ..., yaw_rad: _Optional[float] = ..., colour: _Optional[_Union[Rgba, _Mapping]] = ...) -> None: ...

class SceneCylinder(_message.Message):
    __slots__ = ("name", "center_x_m", "center_y_m", "radius_m", "height_m", "colour")
    NAME_FIELD_NUMBER: _ClassVar[int]
    CENTER_X_M_FIELD_NUMBER: _ClassVar[int]
    CENTER_Y_M_FIELD_NUMBER: _ClassVar[int]
    RADIUS_M_FIELD_NUMBER: _ClassVar[int]
    HEIGHT_M_FIELD_NUMBER: _ClassVar[int]
    COLOUR_FIELD_NUMBER: _ClassVar[int]
    name: str
    center_x_m: float
    center_y_m: float
    radius_m: float
    height_m: float
    colour: Rgba
    def __init__(self, name: _Optional[str] = ..., center_x_m: _Optional[float] = ..., center_y_m: _Optional[float] = ..., radius_m: _Optional[float] = ..., height_m: _Optional[float] = ..., colour: _Optional[_Union[Rgba, _Mapping]] = ...) -> None: ...

class TrackLine(_message.Message):
    __slots__ = ("x1_m", "y1_m", "x2_m", "y2_m", "half_width_m")
    X1_M_FIELD_NUMBER: _ClassVar[int]
    Y1_M_FIELD_NUMBER: _ClassVar[int]
    X2_M_FIELD_NUMBER: _ClassVar[int]
    Y2_M_FIELD_NUMBER: _ClassVar[int]
    HALF_WIDTH_M_FIELD_NUMBER: _ClassVar[int]
    x1_m: float
    y1_m: float
    x2_m: float
    y2_m: float
    half_width_m: float
    def __init__(self, x1_m: _Optional[float] = ..., y1_m: _Optional[float] = ..., x2_m: _Optional[float] = ..., y2_m: _Optional[float] = ..., half_width_m: _Optional[float] = ...) -> None: ...

class TrackLayout(_message.Message):
    __slots__ = ("a_x_m", "a_y_m", "b_x_m", "b_y_m", "round_trip", "arrival_radius_m", "lines")
    A_X_M_FIELD_NUMBER: _ClassVar[int]
    A_Y_M_FIELD_NUMBER: _ClassVar[int]
    B_X_M_FIELD_NUMBER: _ClassVar[int]
    B_Y_M_FIELD_NUMBER: _ClassVar[int]
    ROUND_TRIP_FIELD_NUMBER: _ClassVar[int]
    ARRIVAL_RADIUS_M_FIELD_NUMBER: _ClassVar[int]
    LINES_FIELD_NUMBER: _ClassVar[int]
    a_x_m: float
    a_y_m: float
    b_x_m: float
    b_y_m: float
    round_trip: bool
    arrival_radius_m: float
    lines: _containers.RepeatedCompositeFieldContainer[TrackLine]
    def __init__(self, a_x_m: _Optional[float] = ..., a_y_m: _Optional[float] = ..., b_x_m: _Optional[float] = ..., b_y_m: _Optional[float] = ..., round_trip: _Optional[bool] = ..., arrival_radius_m: _Optional[float] = ..., lines: _Optional[_Iterable[_Union[TrackLine, _Mapping]]] = ...) -> None: ...

class RobotPart(_message.Message):
    __slots__ = ("link", "shape", "size_x_m", "size_y_m", "size_z_m", "position_m", "orientation", "colour")
    LINK_FIELD_NUMBER: _ClassVar[int]
    SHAPE_FIELD_NUMBER: _ClassVar[int]
    SIZE_X_M_FIELD_NUMBER: _ClassVar[int]
    SIZE_Y_M_FIELD_NUMBER: _ClassVar[int]
    SIZE_Z_M_FIELD_NUMBER: _ClassVar[int]
    POSITION_M_FIELD_NUMBER: _ClassVar[int]
    ORIENTATION_FIELD_NUMBER: _ClassVar[int]
    COLOUR_FIELD_NUMBER: _ClassVar[int]
    link: str
    shape: PartShape
    size_x_m: float
    size_y_m: float
    size_z_m: float
    position_m: Vector3
    orientation: Quaternion
    colour: Rgba
    def __init__(self, link: _Optional[str] = ..., shape: _Optional[_Union[PartShape, str]] = ..., size_x_m: _Optional[float] = ..., size_y_m: _Optional[float] = ..., size_z_m: _Optional[float] = ..., position_m: _Optional[_Union[Vector3, _Mapping]] = ..., orientation: _Optional[_Union[Quaternion, _Mapping]] = ..., colour: _Optional[_Union[Rgba, _Mapping]] = ...) -> None: ...

class CameraModel(_message.Message):
    __slots__ = ("width_px", "height_px", "hfov_deg", "vfov_deg", "near_m", "far_m", "mount_forward_m", "mount_height_m", "mount_pitch_rad", "light_direction", "light_ambient", "light_diffuse", "light_specular", "specular_exponent", "background", "sample_offset_x_px", "sample_offset_y_px")
    WIDTH_PX_FIELD_NUMBER: _ClassVar[int]
    HEIGHT_PX_FIELD_NUMBER: _ClassVar[int]
    HFOV_DEG_FIELD_NUMBER: _ClassVar[int]
    VFOV_DEG_FIELD_NUMBER: _ClassVar[int]
    NEAR_M_FIELD_NUMBER: _ClassVar[int]
    FAR_M_FIELD_NUMBER: _ClassVar[int]
    MOUNT_FORWARD_M_FIELD_NUMBER: _ClassVar[int]
    MOUNT_HEIGHT_M_FIELD_NUMBER: _ClassVar[int]
    MOUNT_PITCH_RAD_FIELD_NUMBER: _ClassVar[int]
    LIGHT_DIRECTION_FIELD_NUMBER: _ClassVar[int]
    LIGHT_AMBIENT_FIELD_NUMBER: _ClassVar[int]
    LIGHT_DIFFUSE_FIELD_NUMBER: _ClassVar[int]
    LIGHT_SPECULAR_FIELD_NUMBER: _ClassVar[int]
    SPECULAR_EXPONENT_FIELD_NUMBER: _ClassVar[int]
    BACKGROUND_FIELD_NUMBER: _ClassVar[int]
    SAMPLE_OFFSET_X_PX_FIELD_NUMBER: _ClassVar[int]
    SAMPLE_OFFSET_Y_PX_FIELD_NUMBER: _ClassVar[int]
    width_px: int
    height_px: int
    hfov_deg: float
    vfov_deg: float
    near_m: float
    far_m: float
    mount_forward_m: float
    mount_height_m: float
    mount_pitch_rad: float
    light_direction: Vector3
    light_ambient: float
    light_diffuse: float
    light_specular: float
    specular_exponent: float
    background: Rgba
    sample_offset_x_px: float
    sample_offset_y_px: float
    def __init__(self, width_px: _Optional[int] = ..., height_px: _Optional[int] = ..., hfov_deg: _Optional[float] = ..., vfov_deg: _Optional[float] = ..., near_m: _Optional[float] = ..., far_m: _Optional[float] = ..., mount_forward_m: _Optional[float] = ..., mount_height_m: _Optional[float] = ..., mount_pitch_rad: _Optional[float] = ..., light_direction: _Optional[_Union[Vector3, _Mapping]] = ..., light_ambient: _Optional[float] = ..., light_diffuse: _Optional[float] = ..., light_specular: _Optional[float] = ..., specular_exponent: _Optional[float] = ..., background: _Optional[_Union[Rgba, _Mapping]] = ..., sample_offset_x_px: _Optional[float] = ..., sample_offset_y_px: _Optional[float] = ...) -> None: ...

class SonarRing(_message.Message):
    __slots__ = ("mount_radius_m", "height_m", "sonars")
    MOUNT_RADIUS_M_FIELD_NUMBER: _ClassVar[int]
    HEIGHT_M_FIELD_NUMBER: _ClassVar[int]
    SONARS_FIELD_NUMBER: _ClassVar[int]
    mount_radius_m: float
    height_m: float
    sonars: _containers.RepeatedCompositeFieldContainer[SonarGeometry]
    def __init__(self, mount_radius_m: _Optional[float] = ..., height_m: _Optional[float] = ..., sonars: _Optional[_Iterable[_Union[SonarGeometry, _Mapping]]] = ...) -> None: ...

class SceneDescription(_message.Message):
    __slots__ = ("version", "unchanged", "scene_name", "floor", "marks", "blocks", "cylinders", "track", "spawn", "body_radius_m", "robot_parts", "camera", "laser", "sonar", "room_cameras")
    VERSION_FIELD_NUMBER: _ClassVar[int]
    UNCHANGED_FIELD_NUMBER: _ClassVar[int]
    SCENE_NAME_FIELD_NUMBER: _ClassVar[int]
    FLOOR_FIELD_NUMBER: _ClassVar[int]
    MARKS_FIELD_NUMBER: _ClassVar[int]
    BLOCKS_FIELD_NUMBER: _ClassVar[int]
    CYLINDERS_FIELD_NUMBER: _ClassVar[int]
    TRACK_FIELD_NUMBER: _ClassVar[int]
    SPAWN_FIELD_NUMBER: _ClassVar[int]
    BODY_RADIUS_M_FIELD_NUMBER: _ClassVar[int]
    ROBOT_PARTS_FIELD_NUMBER: _ClassVar[int]
    CAMERA_FIELD_NUMBER: _ClassVar[int]
    LASER_FIELD_NUMBER: _ClassVar[int]
    SONAR_FIELD_NUMBER: _ClassVar[int]
    ROOM_CAMERAS_FIELD_NUMBER: _ClassVar[int]
    version: str
    unchanged: bool
    scene_name: str
    floor: FloorPatch
    marks: _containers.RepeatedCompositeFieldContainer[FloorPatch]
    blocks: _containers.RepeatedCompositeFieldContainer[SceneBlock]
    cylinders: _containers.RepeatedCompositeFieldContainer[SceneCylinder]
    track: TrackLayout
    spawn: Pose2D
    body_radius_m: float
    robot_parts: _containers.RepeatedCompositeFieldContainer[RobotPart]
    camera: CameraModel
    laser: LaserGeometry
    sonar: SonarRing
    room_cameras: _containers.RepeatedCompositeFieldContainer[RoomCamera]
    def __init__(self, version: _Optional[str] = ..., unchanged: _Optional[bool] = ..., scene_name: _Optional[str] = ..., floor: _Optional[_Union[FloorPatch, _Mapping]] = ..., marks: _Optional[_Iterable[_Union[FloorPatch, _Mapping]]] = ..., blocks: _Optional[_Iterable[_Union[SceneBlock, _Mapping]]] = ..., cylinders: _Optional[_Iterable[_Union[SceneCylinder, _Mapping]]] = ..., track: _Optional[_Union[TrackLayout, _Mapping]] = ..., spawn: _Optional[_Union[Pose2D, _Mapping]] = ..., body_radius_m: _Optional[float] = ..., robot_parts: _Optional[_Iterable[_Union[RobotPart, _Mapping]]] = ..., camera: _Optional[_Union[CameraModel, _Mapping]] = ..., laser: _Optional[_Union[LaserGeometry, _Mapping]] = ..., sonar: _Optional[_Union[SonarRing, _Mapping]] = ..., room_cameras: _Optional[_Iterable[_Union[RoomCamera, _Mapping]]] = ...) -> None: ...

class RoomCamera(_message.Message):
    __slots__ = ("id", "title", "x_m", "y_m", "z_m", "pan_rad", "tilt_rad", "hfov_deg", "pan_range_rad", "min_tilt_rad", "max_tilt_rad", "min_hfov_deg", "max_hfov_deg")
    ID_FIELD_NUMBER: _ClassVar[int]
    TITLE_FIELD_NUMBER: _ClassVar[int]
    X_M_FIELD_NUMBER: _ClassVar[int]
    Y_M_FIELD_NUMBER: _ClassVar[int]
    Z_M_FIELD_NUMBER: _ClassVar[int]
    PAN_RAD_FIELD_NUMBER: _ClassVar[int]
    TILT_RAD_FIELD_NUMBER: _ClassVar[int]
    HFOV_DEG_FIELD_NUMBER: _ClassVar[int]
    PAN_RANGE_RAD_FIELD_NUMBER: _ClassVar[int]
    MIN_TILT_RAD_FIELD_NUMBER: _ClassVar[int]
    MAX_TILT_RAD_FIELD_NUMBER: _ClassVar[int]
    MIN_HFOV_DEG_FIELD_NUMBER: _ClassVar[int]
    MAX_HFOV_DEG_FIELD_NUMBER: _ClassVar[int]
    id: str
    title: str
    x_m: float
    y_m: float
    z_m: float
    pan_rad: float
    tilt_rad: float
    hfov_deg: float
    pan_range_rad: float
    min_tilt_rad: float
    max_tilt_rad: float
    min_hfov_deg: float
    max_hfov_deg: float
    def __init__(self, id: _Optional[str] = ..., title: _Optional[str] = ..., x_m: _Optional[float] = ..., y_m: _Optional[float] = ..., z_m: _Optional[float] = ..., pan_rad: _Optional[float] = ..., tilt_rad: _Optional[float] = ..., hfov_deg: _Optional[float] = ..., pan_range_rad: _Optional[float] = ..., min_tilt_rad: _Optional[float] = ..., max_tilt_rad: _Optional[float] = ..., min_hfov_deg: _Optional[float] = ..., max_hfov_deg: _Optional[float] = ...) -> None: ...

class RunPlanRequest(_message.Message):
    __slots__ = ("token", "name", "plan", "preempt")
    TOKEN_FIELD_NUMBER: _ClassVar[int]
    NAME_FIELD_NUMBER: _ClassVar[int]
    PLAN_FIELD_NUMBER: _ClassVar[int]
    PREEMPT_FIELD_NUMBER: _ClassVar[int]
    token: str
    name: str
    plan: PlanBlock
    preempt: bool
    def __init__(self, token: _Optional[str] = ..., name: _Optional[str] = ..., plan: _Optional[_Union[PlanBlock, _Mapping]] = ..., preempt: _Optional[bool] = ...) -> None: ...

class PlanBlock(_message.Message):
    __slots__ = ("steps",)
    STEPS_FIELD_NUMBER: _ClassVar[int]
    steps: _containers.RepeatedCompositeFieldContainer[PlanStep]
    def __init__(self, steps: _Optional[_Iterable[_Union[PlanStep, _Mapping]]] = ...) -> None: ...

class PlanStep(_message.Message):
    __slots__ = ("line", "column", "skill", "drive", "wait", "repeat", "branch", "set", "say", "on")
    LINE_FIELD_NUMBER: _ClassVar[int]
    COLUMN_FIELD_NUMBER: _ClassVar[int]
    SKILL_FIELD_NUMBER: _ClassVar[int]
    DRIVE_FIELD_NUMBER: _ClassVar[int]
    WAIT_FIELD_NUMBER: _ClassVar[int]
    REPEAT_FIELD_NUMBER: _ClassVar[int]
    BRANCH_FIELD_NUMBER: _ClassVar[int]
    SET_FIELD_NUMBER: _ClassVar[int]
    SAY_FIELD_NUMBER: _ClassVar[int]
    ON_FIELD_NUMBER: _ClassVar[int]
    line: int
    column: int
    skill: SkillStep
    drive: DriveStep
    wait: WaitStep
    repeat: RepeatStep
    branch: IfStep
    set: SetStep
    say: SayStep
    on: OnStep
    def __init__(self, line: _Optional[int] = ..., column: _Optional[int] = ..., skill: _Optional[_Union[SkillStep, _Mapping]] = ..., drive: _Optional[_Union[DriveStep, _Mapping]] = ..., wait: _Optional[_Union[WaitStep, _Mapping]] = ..., repeat: _Optional[_Union[RepeatStep, _Mapping]] = ..., branch: _Optional[_Union[IfStep, _Mapping]] = ..., set: _Optional[_Union[SetStep, _Mapping]] = ..., say: _Optional[_Union[SayStep, _Mapping]] = ..., on: _Optional[_Union[OnStep, _Mapping]] = ...) -> None: ...

class OnStep(_message.Message):
    __slots__ = ("event", "value", "body")
    EVENT_FIELD_NUMBER: _ClassVar[int]
    VALUE_FIELD_NUMBER: _ClassVar[int]
    BODY_FIELD_NUMBER: _ClassVar[int]
    event: str
    value: float
    body: PlanBlock
    def __init__(self, event: _Optional[str] = ..., value: _Optional[float] = ..., body: _Optional[_Union[PlanBlock, _Mapping]] = ...) -> None: ...

class SkillStep(_message.Message):
    __slots__ = ("skill", "parameters", "duration_s")
    class ParametersEntry(_message.Message):
        __slots__ = ("key", "value")
        KEY_FIELD_NUMBER: _ClassVar[int]
        VALUE_FIELD_NUMBER: _ClassVar[int]
        key: str
        value: ParameterValue
        def __init__(self, key: _Optional[str] = ..., value: _Optional[_Union[ParameterValue, _Mapping]] = ...) -> None: ...
    SKILL_FIELD_NUMBER: _ClassVar[int]
    PARAMETERS_FIELD_NUMBER: _ClassVar[int]
    DURATION_S_FIELD_NUMBER: _ClassVar[int]
    skill: str
    parameters: _containers.MessageMap[str, ParameterValue]
    duration_s: float
    def __init__(self, skill: _Optional[str] = ..., parameters: _Optional[_Mapping[str, ParameterValue]] = ..., duration_s: _Optional[float] = ...) -> None: ...

class DriveStep(_message.Message):
    __slots__ = ("linear_mps", "angular_radps", "duration_s")
    LINEAR_MPS_FIELD_NUMBER: _ClassVar[int]
    ANGULAR_RADPS_FIELD_NUMBER: _ClassVar[int]
    DURATION_S_FIELD_NUMBER: _ClassVar[int]
    linear_mps: float
    angular_radps: float
    duration_s: float
    def __init__(self, linear_mps: _Optional[float] = ..., angular_radps: _Optional[float] = ..., duration_s: _Optional[float] = ...) -> None: ...

class WaitStep(_message.Message):
    __slots__ = ("condition", "duration_s")
    CONDITION_FIELD_NUMBER: _ClassVar[int]
    DURATION_S_FIELD_NUMBER: _ClassVar[int]
    condition: PlanCondition
    duration_s: float
    def __init__(self, condition: _Optional[_Union[PlanCondition, _Mapping]] = ..., duration_s: _Optional[float] = ...) -> None: ...

class RepeatStep(_message.Message):
    __slots__ = ("count", "body")
    COUNT_FIELD_NUMBER: _ClassVar[int]
    BODY_FIELD_NUMBER: _ClassVar[int]
    count: int
    body: PlanBlock
    def __init__(self, count: _Optional[int] = ..., body: _Optional[_Union[PlanBlock, _Mapping]] = ...) -> None: ...

class IfStep(_message.Message):
    __slots__ = ("condition", "then_block", "else_block")
    CONDITION_FIELD_NUMBER: _ClassVar[int]
    THEN_BLOCK_FIELD_NUMBER: _ClassVar[int]
    ELSE_BLOCK_FIELD_NUMBER: _ClassVar[int]
    condition: PlanCondition
    then_block: PlanBlock
    else_block: PlanBlock
    def __init__(self, condition: _Optional[_Union[PlanCondition, _Mapping]] = ..., then_block: _Optional[_Union[PlanBlock, _Mapping]] = ..., else_block: _Optional[_Union[PlanBlock, _Mapping]] = ...) -> None: ...

class PlanCondition(_message.Message):
    __slots__ = ("kind", "value", "negate")
    KIND_FIELD_NUMBER: _ClassVar[int]
    VALUE_FIELD_NUMBER: _ClassVar[int]
    NEGATE_FIELD_NUMBER: _ClassVar[int]
    kind: str
    value: float
    negate: bool
    def __init__(self, kind: _Optional[str] = ..., value: _Optional[float] = ..., negate: _Optional[bool] = ...) -> None: ...

class SetStep(_message.Message):
    __slots__ = ("setting", "value")
    SETTING_FIELD_NUMBER: _ClassVar[int]
    VALUE_FIELD_NUMBER: _ClassVar[int]
    setting: str
    value: float
    def __init__(self, setting: _Optional[str] = ..., value: _Optional[float] = ...) -> None: ...

class SayStep(_message.Message):
    __slots__ = ("text",)
    TEXT_FIELD_NUMBER: _ClassVar[int]
    text: str
    def __init__(self, text: _Optional[str] = ...) -> None: ...

class SetLimitsRequest(_message.Message):
    __slots__ = ("token", "max_linear_mps", "max_angular_radps", "watchdog_s")
    TOKEN_FIELD_NUMBER: _ClassVar[int]
    MAX_LINEAR_MPS_FIELD_NUMBER: _ClassVar[int]
    MAX_ANGULAR_RADPS_FIELD_NUMBER: _ClassVar[int]
    WATCHDOG_S_FIELD_NUMBER: _ClassVar[int]
    token: str
    max_linear_mps: float
    max_angular_radps: float
    watchdog_s: float
    def __init__(self, token: _Optional[str] = ..., max_linear_mps: _Optional[float] = ..., max_angular_radps: _Optional[float] = ..., watchdog_s: _Optional[float] = ...) -> None: ...

class GetLimitsRequest(_message.Message):
    __slots__ = ()
    def __init__(self) -> None: ...

class Limits(_message.Message):
    __slots__ = ("max_linear_mps", "max_angular_radps", "watchdog_s", "robot_max_linear_mps", "robot_max_angular_radps", "min_watchdog_s", "max_watchdog_s")
    MAX_LINEAR_MPS_FIELD_NUMBER: _ClassVar[int]
    MAX_ANGULAR_RADPS_FIELD_NUMBER: _ClassVar[int]
    WATCHDOG_S_FIELD_NUMBER: _ClassVar[int]
    ROBOT_MAX_LINEAR_MPS_FIELD_NUMBER: _ClassVar[int]
    ROBOT_MAX_ANGULAR_RADPS_FIELD_NUMBER: _ClassVar[int]
    MIN_WATCHDOG_S_FIELD_NUMBER: _ClassVar[int]
    MAX_WATCHDOG_S_FIELD_NUMBER: _ClassVar[int]
    max_linear_mps: float
    max_angular_radps: float
    watchdog_s: float
    robot_max_linear_mps: float
    robot_max_angular_radps: float
    min_watchdog_s: float
    max_watchdog_s: float
    def __init__(self, max_linear_mps: _Optional[float] = ..., max_angular_radps: _Optional[float] = ..., watchdog_s: _Optional[float] = ..., robot_max_linear_mps: _Optional[float] = ..., robot_max_angular_radps: _Optional[float] = ..., min_watchdog_s: _Optional[float] = ..., max_watchdog_s: _Optional[float] = ...) -> None: ...

class GetEvidenceGridRequest(_message.Message):
    __slots__ = ("watch", "sensor", "part")
    WATCH_FIELD_NUMBER: _ClassVar[int]
    SENSOR_FIELD_NUMBER: _ClassVar[int]
    PART_FIELD_NUMBER: _ClassVar[int]
    watch: bool
    sensor: EvidenceSensor
    part: EvidencePart
    def __init__(self, watch: _Optional[bool] = ..., sensor: _Optional[_Union[EvidenceSensor, str]] = ..., part: _Optional[_Union[EvidencePart, str]] = ...) -> None: ...

class ResetEvidenceGridRequest(_message.Message):
    __slots__ = ("token",)
    TOKEN_FIELD_NUMBER: _ClassVar[int]
    token: str
    def __init__(self, token: _Optional[str] = ...) -> None: ...

class EvidenceGrid(_message.Message):
    __slots__ = ("grid", "sonar_scans", "laser_scans", "static_scans", "moving_scans", "odometry", "accumulating", "version")
    GRID_FIELD_NUMBER: _ClassVar[int]
    SONAR_SCANS_FIELD_NUMBER: _ClassVar[int]
    LASER_SCANS_FIELD_NUMBER: _ClassVar[int]
    STATIC_SCANS_FIELD_NUMBER: _ClassVar[int]
    MOVING_SCANS_FIELD_NUMBER: _ClassVar[int]
    ODOMETRY_FIELD_NUMBER: _ClassVar[int]
    ACCUMULATING_FIELD_NUMBER: _ClassVar[int]
    VERSION_FIELD_NUMBER: _ClassVar[int]
    grid: OccupancyGrid
    sonar_scans: int
    laser_scans: int
    static_scans: int
    moving_scans: int
    odometry: Pose2D
    accumulating: bool
    version: int
    def __init__(self, grid: _Optional[_Union[OccupancyGrid, _Mapping]] = ..., sonar_scans: _Optional[int] = ..., laser_scans: _Optional[int] = ..., static_scans: _Optional[int] = ..., moving_scans: _Optional[int] = ..., odometry: _Optional[_Union[Pose2D, _Mapping]] = ..., accumulating: _Optional[bool] = ..., version: _Optional[int] = ...) -> None: ...

class GetPerceptionReadingsRequest(_message.Message):
    __slots__ = ("after_index",)
    AFTER_INDEX_FIELD_NUMBER: _ClassVar[int]
    after_index: int
    def __init__(self, after_index: _Optional[int] = ...) -> None: ...

class PerceptionScan(_message.Message):
    __slots__ = ("index", "capture_unix_s", "sim_time_s", "odometry", "part", "sonar_ranges_m", "laser_ranges_m")
    INDEX_FIELD_NUMBER: _ClassVar[int]
    CAPTURE_UNIX_S_FIELD_NUMBER: _ClassVar[int]
    SIM_TIME_S_FIELD_NUMBER: _ClassVar[int]
    ODOMETRY_FIELD_NUMBER: _ClassVar[int]
    PART_FIELD_NUMBER: _ClassVar[int]
    SONAR_RANGES_M_FIELD_NUMBER: _ClassVar[int]
    LASER_RANGES_M_FIELD_NUMBER: _ClassVar[int]
    index: int
    capture_unix_s: float
    sim_time_s: float
    odometry: Pose2D
    part: EvidencePart
    sonar_ranges_m: _containers.RepeatedScalarFieldContainer[float]
    laser_ranges_m: _containers.RepeatedScalarFieldContainer[float]
    def __init__(self, index: _Optional[int] = ..., capture_unix_s: _Optional[float] = ..., sim_time_s: _Optional[float] = ..., odometry: _Optional[_Union[Pose2D, _Mapping]] = ..., part: _Optional[_Union[EvidencePart, str]] = ..., sonar_ranges_m: _Optional[_Iterable[float]] = ..., laser_ranges_m: _Optional[_Iterable[float]] = ...) -> None: ...

class PerceptionReadings(_message.Message):
    __slots__ = ("scans",)
    SCANS_FIELD_NUMBER: _ClassVar[int]
    scans: _containers.RepeatedCompositeFieldContainer[PerceptionScan]
    def __init__(self, scans: _Optional[_Iterable[_Union[PerceptionScan, _Mapping]]] = ...) -> None: ...
