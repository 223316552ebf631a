from google.protobuf.internal import containers as _containers
from google.protobuf.internal import enum_type_wrapper as _enum_type_wrapper
from google.protobuf import descriptor as _descriptor
from google.protobuf import message as _message
from collections.abc import Iterable as _Iterable, Mapping as _Mapping
from typing import ClassVar as _ClassVar, Optional as _Optional, Union as _Union

DESCRIPTOR: _descriptor.FileDescriptor

class ParameterType(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = ()
    PARAMETER_TYPE_UNSPECIFIED: _ClassVar[ParameterType]
    PARAMETER_TYPE_DOUBLE: _ClassVar[ParameterType]
    PARAMETER_TYPE_INT: _ClassVar[ParameterType]
    PARAMETER_TYPE_BOOL: _ClassVar[ParameterType]
    PARAMETER_TYPE_ENUM: _ClassVar[ParameterType]
PARAMETER_TYPE_UNSPECIFIED: ParameterType
PARAMETER_TYPE_DOUBLE: ParameterType
PARAMETER_TYPE_INT: ParameterType
PARAMETER_TYPE_BOOL: ParameterType
PARAMETER_TYPE_ENUM: ParameterType

class GetRobotInfoRequest(_message.Message):
    __slots__ = ()
    def __init__(self) -> None: ...

class RobotInfo(_message.Message):
    __slots__ = ("robot_name", "scene_name", "wheel_base_m", "wheel_radius_m", "body_radius_m", "max_linear_mps", "max_angular_radps", "deadman_timeout_s", "camera_hfov_deg", "camera_width_px", "camera_height_px", "sonars", "laser", "scene_boxes")
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
    def __init__(self, robot_name: _Optional[str] = ..., scene_name: _Optional[str] = ..., wheel_base_m: _Optional[float] = ..., wheel_radius_m: _Optional[float] = ..., body_radius_m: _Optional[float] = ..., max_linear_mps: _Optional[float] = ..., max_angular_radps: _Optional[float] = ..., deadman_timeout_s: _Optional[float] = ..., camera_hfov_deg: _Optional[float] = ..., camera_width_px: _Optional[int] = ..., camera_height_px: _Optional[int] = ..., sonars: _Optional[_Iterable[_Union[SonarGeometry, _Mapping]]] = ..., laser: _Optional[_Union[LaserGeometry, _Mapping]] = ..., scene_boxes: _Optional[_Iterable[_Union[SceneBox, _Mapping]]] = ...) -> None: ...

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
    __slots__ = ("angle_min_rad", "angle_max_rad", "beam_count", "min_range_m", "max_range_m")
    ANGLE_MIN_RAD_FIELD_NUMBER: _ClassVar[int]
    ANGLE_MAX_RAD_FIELD_NUMBER: _ClassVar[int]
    BEAM_COUNT_FIELD_NUMBER: _ClassVar[int]
    MIN_RANGE_M_FIELD_NUMBER: _ClassVar[int]
    MAX_RANGE_M_FIELD_NUMBER: _ClassVar[int]
    angle_min_rad: float
    angle_max_rad: float
    beam_count: int
    min_range_m: float
    max_range_m: float
    def __init__(self, angle_min_rad: _Optional[float] = ..., angle_max_rad: _Optional[float] = ..., beam_count: _Optional[int] = ..., min_range_m: _Optional[float] = ..., max_range_m: _Optional[float] = ...) -> None: ...

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
    __slots__ = ("name", "title", "help", "parameters")
    NAME_FIELD_NUMBER: _ClassVar[int]
    TITLE_FIELD_NUMBER: _ClassVar[int]
    HELP_FIELD_NUMBER: _ClassVar[int]
    PARAMETERS_FIELD_NUMBER: _ClassVar[int]
    name: str
    title: str
    help: str
    parameters: _containers.RepeatedCompositeFieldContainer[ParameterSchema]
    def __init__(self, name: _Optional[str] = ..., title: _Optional[str] = ..., help: _Optional[str] = ..., parameters: _Optional[_Iterable[_Union[ParameterSchema, _Mapping]]] = ...) -> None: ...

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

class StreamTelemetryRequest(_message.Message):
    __slots__ = ("rate_hz",)
    RATE_HZ_FIELD_NUMBER: _ClassVar[int]
    rate_hz: float
    def __init__(self, rate_hz: _Optional[float] = ...) -> None: ...

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
    __slots__ = ("tick", "sim_time_s", "capture_unix_s", "last_applied_sequence", "odometry", "ground_truth", "sonar", "laser", "deadman_stopped")
    TICK_FIELD_NUMBER: _ClassVar[int]
    SIM_TIME_S_FIELD_NUMBER: _ClassVar[int]
    CAPTURE_UNIX_S_FIELD_NUMBER: _ClassVar[int]
    LAST_APPLIED_SEQUENCE_FIELD_NUMBER: _ClassVar[int]
    ODOMETRY_FIELD_NUMBER: _ClassVar[int]
    GROUND_TRUTH_FIELD_NUMBER: _ClassVar[int]
    SONAR_FIELD_NUMBER: _ClassVar[int]
    LASER_FIELD_NUMBER: _ClassVar[int]
    DEADMAN_STOPPED_FIELD_NUMBER: _ClassVar[int]
    tick: int
    sim_time_s: float
    capture_unix_s: float
    last_applied_sequence: int
    odometry: Odometry
    ground_truth: Pose2D
    sonar: SonarReading
    laser: LaserScan
    deadman_stopped: bool
    def __init__(self, tick: _Optional[int] = ..., sim_time_s: _Optional[float] = ..., capture_unix_s: _Optional[float] = ..., last_applied_sequence: _Optional[int] = ..., odometry: _Optional[_Union[Odometry, _Mapping]] = ..., ground_truth: _Optional[_Union[Pose2D, _Mapping]] = ..., sonar: _Optional[_Union[SonarReading, _Mapping]] = ..., laser: _Optional[_Union[LaserScan, _Mapping]] = ..., deadman_stopped: _Optional[bool] = ...) -> None: ...

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
