"""The plan the simulation takes: plain frozen data, every path absolute, every time in steps.

Loading and resolving (``mobot_cli.scenario``, ``mobot_cli.assets``) produce these; the
simulation core consumes them and never reads YAML or searches for files.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

CAMERA_KINDS = ("camera", "depth", "rgbd")  # SensorSpec.kind of a camera (docs/cameras.md)


@dataclass(frozen=True)
class FaultLimits:
    """When a robot's motion is a fault that ends the run (docs/faults.md), and how far its
    odometry may stray from the truth before a notice says so; a scenario's ``faults:``."""

    max_tilt: float = math.radians(60.0)  # rad: roll or pitch beyond this is tipped over
    flying_time: float = 1.0  # s touching nothing while above where it last touched something
    max_speed: float = 20.0  # m/s of the root link, or twice the fastest command if more
    odom_tolerance: float = 0.25  # m between odometry and ground truth


@dataclass(frozen=True)
class Physics:
    """Fixed-step physics settings."""

    rate_hz: int = 240
    gravity: tuple[float, float, float] = (0.0, 0.0, -9.81)
    solver_iterations: int = 50
    # "bullet": wheels driven by torques through PyBullet's solver (sim/bullet/world.py);
    # "kinematic": robots follow their commanded twist (sim/kinematic/world.py)
    engine: str = "bullet"
    faults: FaultLimits = FaultLimits()  # checked by the World, so every door gets them
    renderer: str = "auto"  # cameras: "auto" | "tiny" | "egl" (sim/sensing/render.py)

    @property
    def dt(self) -> float:
        return 1.0 / self.rate_hz


@dataclass(frozen=True)
class SpawnPose:
    """Where a robot's root link starts, in the world frame; quaternion is (x, y, z, w) as in ROS."""

    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    quat: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0)
    z_auto: bool = False  # when true, xyz[2] is ignored: rest the lowest collision point on the floor


@dataclass(frozen=True)
class DriveSpec:
    """A robot's drive, fully resolved: detected values merged with overrides.

    ``kind`` says how wheel speeds follow a body twist (docs/drives.md has the table):
    "diff" (one wheel a side), "skid" (several a side, scrubbing in turns), "mecanum" and "omni"
    (holonomic: they also take a sideways ``linear_y``), "ackermann" (steered front wheels,
    ``steering_joints``, driven ``left_joints``/``right_joints``). Every kind lists its wheels in
    ``left_joints`` and ``right_joints``, front first. A scenario's ``drive.type`` (DESIGN.md) is
    ``diff`` (diff or skid), ``holonomic`` (mecanum or omni) or ``ackermann``.
    """

    left_joints: tuple[str, ...]
    right_joints: tuple[str, ...]
    wheel_radius: float  # metres
    wheel_separation: float  # metres, between left and right wheel contact lines
    wheel_separation_multiplier: float = 1.0  # as ros2_control's diff_drive_controller
    wheel_radius_multiplier: float = 1.0
    max_wheel_torque: float = 20.0  # N*m per wheel
    max_wheel_acceleration: float | None = None  # rad/s^2 at the wheel; None = unlimited
    odometry: str = "encoder"  # "encoder" | "ground_truth": what odom_* reports
    # Trim wheel speeds until the measured body twist matches the command (sim/bullet/twist_trim.py);
    # None: on for skid steer (more than one wheel per side), off for two wheels.
    twist_feedback: bool | None = None
    # Where the wheel layout came from ("urdf" | "plugin" | "scenario"): a note, not a setting.
    source: str = field(default="urdf", compare=False)
    # joint name -> +1.0 / -1.0: a positive joint velocity times the sign rolls that wheel
    # forward (+x of the root link). A wheel whose axis points along -y needs -1.0.
    # Joints not listed count as +1.0.
    joint_signs: tuple[tuple[str, float], ...] = ()
    kind: str = "diff"  # "diff" | "skid" | "mecanum" | "omni" | "ackermann"
    wheelbase: float = 0.0  # metres between the front and rear axles (mecanum, omni, ackermann)
    steering_joints: tuple[str, ...] = ()  # ackermann: (left, right) steering joints
    max_steering_angle: float | None = None  # rad, ackermann: the steering joints' limit
    # Where max_wheel_torque came from: "scenario" (drive.max_wheel_torque), "plugin" (its torque),
    # "urdf" (the wheel joints' <limit effort>), "mass" (mobot's default for the robot's mass,
    # assets/description/torque.py) or "default" (20 N*m: a drive made without a description).
    torque_source: str = field(default="default", compare=False)


@dataclass(frozen=True)
class CommandStep:
    """From physics step ``step`` on, command this body twist (m/s, rad/s) until the next one."""

    step: int
    linear: float
    angular: float
    linear_y: float = 0.0  # m/s sideways (+y, left): holonomic drives only


@dataclass(frozen=True)
class GoalControl:
    """How a goal command drives (see timeline/pursuit.py): limits, tolerances, what pose it trusts."""

    max_linear: float = 0.3  # m/s
    max_angular: float = 1.0  # rad/s
    linear_acceleration: float = 0.5  # m/s^2
    angular_acceleration: float = 2.0  # rad/s^2
    tolerance: float = 0.05  # m: how close counts as there (the last point; sharp corners on the way)
    yaw_tolerance: float = 0.05  # rad, for a goal's final heading
    localization: str = "odometry"  # "odometry" (the robot's own odom_*) | "ground_truth"
    timeout: int | None = None  # physics steps from the start; None: no limit
    planner: str | None = None  # "astar": plan around the world's obstacles (timeline/planner.py); None: straight
    inflation: float = 0.0  # m: the planner keeps the robot's centre this far from obstacles
    local: str = ""  # "" (follow the route as it is) | "dwb" (avoid what the lidar sees: timeline/local.py)
    stuck_time: float = 1.0  # s without progress (true pose) after which the goal ends blocked (stuck)
    danger_distance: float = 0.3  # m: the metrics' danger_time counts the time closer than this


@dataclass(frozen=True)
class GoalStep:
    """A goal command: from ``step`` on (or when the goal before it ends, if later), drive along
    ``points`` (world x, y) with a pursuit controller until the last one is reached."""

    step: int
    index: int  # its place in the robot's ``commands:`` list: records and ``goal:`` checks name it
    kind: str  # "goto" | "path" | "patrol" | "coverage"
    points: tuple[tuple[float, float], ...]  # goto: the goal; coverage: the planned lanes
    yaw: float | None = None  # goto: the heading to turn to once there
    laps: int | None = None  # patrol: rounds of points[0] .. points[-1] and back; None: until the end
    area: tuple[tuple[float, float], ...] = ()  # coverage: the area as a polygon
    spacing: float = 0.0  # coverage: the largest distance between lanes
    control: GoalControl = GoalControl()


@dataclass(frozen=True)
class TwistStep:
    """A twist command that follows a goal: from ``step`` on, or when that goal ends if later;
    a stop after ``hold`` steps (None: it holds until the next command)."""

    step: int
    index: int
    linear: float
    angular: float
    hold: int | None = None
    linear_y: float = 0.0  # m/s sideways: holonomic drives only


@dataclass(frozen=True)
class RayAxis:
    """One axis of a ray sensor's scan, as Gazebo's ``<horizontal>`` or ``<vertical>``."""

    samples: int
    min_angle: float  # rad
    max_angle: float  # rad
    resolution: float = 1.0  # Gazebo's multiplier of samples; mobot casts ``samples`` rays


@dataclass(frozen=True)
class SensorSpec:
    """One sensor of a robot, resolved from its ``<gazebo><sensor>`` block and the scenario.

    ``kind`` is "lidar" (Gazebo's ray, gpu_ray, lidar, gpu_lidar; 3D when ``vertical`` has
    more than one sample), "range" (a ray sensor read by a range plugin, or a sonar: one
    distance per reading, the nearest of its rays), "imu" or "contact". Names are unprefixed:
    the robot's namespace and frame prefix are added when the readings are recorded.
    """

    name: str  # the <sensor name>, unique within the robot
    kind: str  # "lidar" | "range" | "imu" | "contact" | "camera" | "depth" | "rgbd"
    link: str  # the link it rides on
    every: int  # physics steps between two readings: update_rate rounded to whole steps
    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)  # pose in the link frame
    quat: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0)
    topic: str = ""  # relative to the robot's namespace, e.g. "scan"
    frame_id: str = ""  # the frame readings are stamped with (default: the link)
    horizontal: RayAxis | None = None  # lidar and range only
    vertical: RayAxis | None = None  # lidar and range only; None or one sample: a 2D scan
    range_min: float = 0.0  # m, lidar and range only
    range_max: float = 0.0
    range_resolution: float = 0.0  # m; 0: ranges are not quantised
    noise_mean: float = 0.0  # gaussian noise on each ray (lidar, range), on angular velocity (imu)
    noise_stddev: float = 0.0
    accel_noise_stddev: float = 0.0  # imu: gaussian noise on linear acceleration (m/s^2)
    collision: str = ""  # contact: the collision element whose contacts count ("" = the whole link)
    source: str = ""  # where it was declared, for messages
    radiation: str = ""  # range: "ultrasound" | "infrared", as sensor_msgs/Range's radiation_type
    field_of_view: float = 0.0  # rad, range: the arc the plugin reports (its rays are the axes')
    reading_noise_stddev: float = 0.0  # m, range: the plugin's gaussian noise on the reading itself
    # cameras ("camera": RGB, "depth": depth only, "rgbd": both; docs/cameras.md): the image size,
    # its sensor_msgs/Image encoding ("rgb8", "bgr8", "mono8"); field_of_view is the horizontal
    # field of view (rad) and range_min/range_max the clip planes (m). The camera looks along the
    # sensor frame's +x (z up), as Gazebo's; its images are in the optical frame (REP 103).
    width: int = 0
    height: int = 0
    encoding: str = ""
    # m: a depth image's own near and far (gz's <depth_camera><clip>): depths beyond it +inf,
    # nearer -inf, as gz-sensors gives them; None: the camera's clip planes bound the depth too
    depth_clip: tuple[float, float] | None = None


@dataclass(frozen=True)
class JointHold:
    """A movable joint (not a drive wheel) that something holds, as Gazebo would.

    "spring": Gazebo's springStiffness / SDF spring_stiffness pulls it toward ``target`` with
    ``stiffness`` (N*m/rad or N/m); its damping stays the URDF's. "position": a position
    controller (ros2_control, a joint plugin) holds it at ``target`` with at most ``effort``.
    """

    joint: str
    kind: str  # "spring" | "position"
    target: float = 0.0  # rad or m: the spring's reference, or the position held (its initial one)
    stiffness: float = 0.0  # spring only
    effort: float = 0.0  # position only: N*m or N, from the joint's <limit effort>
    source: str = ""  # what holds it ("springStiffness", "ros2_control", a plugin's filename)


@dataclass(frozen=True)
class RobotPlan:
    """One robot to spawn: its expanded URDF text and everything needed to drive it."""

    name: str
    namespace: str  # "/name" by default
    frame_prefix: str  # "name/" by default
    urdf: str  # expanded URDF; every mesh filename is an absolute path
    root_link: str
    pose: SpawnPose
    drive: DriveSpec | None
    # CommandSteps first; from the first goal on, GoalSteps and the TwistSteps that wait for them
    commands: tuple[CommandStep | GoalStep | TwistStep, ...] = ()
    spawn_step: int = 0
    source: str = ""  # the description file, for messages
    sensors: tuple[SensorSpec, ...] = ()
    footprint: tuple[float, float, float, float] | None = None  # xmin, xmax, ymin, ymax in its root frame
    heights: tuple[float, float] | None = None  # its collision geometry's lowest and highest z, root frame
    holds: tuple[JointHold, ...] = ()  # springs and held joints (sim/bullet/joints.py)


@dataclass(frozen=True)
class StaticShape:
    """One collision shape of a static body, posed in the body's frame."""

    kind: str  # "box" | "cylinder" | "capsule" | "sphere" | "plane" | "mesh"
    # box: x, y, z sizes; cylinder and capsule: radius, length; sphere: radius;
    # plane: its normal; mesh: the x, y, z scale
    size: tuple[float, ...]
    mesh: str = ""  # absolute path of an OBJ or STL file; it collides as a concave triangle mesh
    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    quat: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0)
    name: str = ""  # as in the world file, scoped in its model: "link::collision" (refusals name it)


@dataclass(frozen=True)
class StaticBody:
    """A piece of static world geometry: collision shapes (SDF worlds) or URDF text."""

    name: str
    urdf: str = ""  # a single-link URDF with absolute mesh paths; used when shapes is empty
    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    quat: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0)
    shapes: tuple[StaticShape, ...] = ()  # a plane is always the only shape of its body
    friction: float | None = None  # None: the world's default (1.0, as Gazebo's mu)
    label: str = ""  # how messages name it, e.g. "world model 'Bed_01_001' at (-6.17, 2.03, 0.00)"


@dataclass(frozen=True)
class MoverPlan:
    """Something that moves by itself (docs/movers.md): a Gazebo ``<actor>`` or a scenario's
    ``movers:`` item. Upright shapes only: a box (turned by its yaw), a cylinder or a person
    (a capsule). It follows ``keyframes`` as Gazebo plays an actor's trajectory, or, with a
    ``region``, walks between random goals in it by the social-force model (sim/movers/social.py)."""

    name: str
    shape: str  # "box" | "cylinder" | "person"
    size: tuple[float, ...]  # box: x, y, z sizes; cylinder and person: radius, height
    # (t in seconds of its script, x, y, yaw): the pose is interpolated between them by time
    keyframes: tuple[tuple[float, float, float, float], ...] = ()
    loop: bool = True  # start again after the last keyframe (after ``delay`` again, as Gazebo's actors)
    delay: float = 0.0  # s before the script starts (Gazebo's <delay_start>)
    auto_start: bool = True  # False: it stays at its first keyframe (nothing in mobot starts it)
    region: tuple[float, float, float, float] | None = None  # walker: xmin, xmax, ymin, ymax of its goals
    speed: float = 1.0  # m/s: a walker's preferred speed
    start: tuple[float, float] | None = None  # walker: where it starts (None: a random point of its region)
    z: float = 0.0  # m: the bottom of its shape
    source: str = ""  # "actor" (from the world file) or "scenario", for messages and records
    spawn_step: int = 0  # scenario movers: when it enters the world
    # Gazebo actors: (first, last keyframe index, tension) of each <trajectory>, played on
    # Gazebo's splines between those keyframes (sim/movers/spline.py); elsewhere straight lines
    curves: tuple[tuple[int, int, float], ...] = ()


@dataclass(frozen=True)
class WorldPlan:
    """The static world: a ground plane and static bodies."""

    name: str = "empty"
    ground_plane: bool = True
    bodies: tuple[StaticBody, ...] = ()
    source: str = ""  # the world file, for messages
    robot_models: tuple[str, ...] = ()  # its models with joints: robots when a scenario lists them
    actors: tuple[MoverPlan, ...] = ()  # its <actor>s with a scripted trajectory (docs/movers.md)


@dataclass(frozen=True)
class Event:
    """At physics step ``step``, spawn a robot or delete one by name (exactly one of the two)."""

    step: int
    spawn: RobotPlan | None = None
    delete: str | None = None


@dataclass(frozen=True)
class Expectation:
    """A check on a run's samples (see timeline/expect.py), from a scenario's ``expect:`` list."""

    robot: str  # a robot's name, or "all": every robot, each checked on its own
    # "within" | "collisions" | "distance" | "upright" | "odom_error" | "clearance" | "reaches"
    # | "visits" | "coverage" | "goal"
    kind: str
    limits: tuple[tuple[str, float], ...]  # e.g. (("x", 5.0), ("y", 1.0), ("radius", 0.3))
    step: int | None = None  # a log row's step; None is the end of the run
    points: tuple[tuple[float, float], ...] = ()  # visits: the checkpoints; coverage: the area
    status: str = ""  # goal: the outcome expected
    metric: str = ""  # metric: its name (limits: min, max, command)

    def limit(self, name: str) -> float | None:
        """One limit by name, or None when the scenario did not give it."""
        return dict(self.limits).get(name)


@dataclass(frozen=True)
class Ros2Settings:
    """How the world joins ROS 2 (``--ros2`` or a scenario's ``ros2:`` block)."""

    node: str = "mobot"
    namespace: str = "/"  # the node's namespace; robots' topics keep their own namespaces
    domain_id: int | None = None  # None: ROS_DOMAIN_ID, else 0
    cmd_vel_timeout_steps: int | None = None  # stop a robot whose /cmd_vel went quiet this long
    ignore_fastdds_type_information: bool = True  # Fast DDS 3 (Kilted) sends some Cyclone cannot parse
    world_frame: bool = True  # world -> <prefix>odom on /tf_static; off when a localizer owns map -> odom
    map: bool = False  # the world's occupancy grid on /map (ros2/map_topic.py)


@dataclass(frozen=True)
class Plan:
    """Everything a run needs, with all times already in whole physics steps."""

    name: str
    physics: Physics
    world: WorldPlan
    robots: tuple[RobotPlan, ...]
    total_steps: int
    settle_steps: int
    log_every: int  # physics steps between two log rows
    seed: int = 0
    formats: tuple[str, ...] = ("csv",)  # what the run folder records besides summary.json
    events: tuple[Event, ...] = ()
    notices: tuple[str, ...] = field(default=())
    expectations: tuple[Expectation, ...] = ()
    ros2: Ros2Settings | None = None  # None: the world does not join ROS 2 unless asked (--ros2)
    # a generated world (``world: {generate: ...}``) as an SDF world file: the run folder keeps it
    generated_world: str = ""
    movers: tuple[MoverPlan, ...] = ()  # the scenario's movers: (docs/movers.md); the world's actors are in world
    # the bag's camera images: "raw" sensor_msgs/Image, or "png"/"jpeg" CompressedImage (docs/cameras.md)
    images: str = "raw"


def renders(plan: Plan) -> bool:
    """Whether any robot of the plan has a camera (its World then takes a PyBullet client of its own)."""
    return any(sensor.kind in CAMERA_KINDS for robot in plan.robots for sensor in robot.sensors)
