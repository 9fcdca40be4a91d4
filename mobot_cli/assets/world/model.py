"""What the SDF reader produces: models flattened into links and joints, and the world."""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field

from mobot_cli.assets.world.geometry import Shape
from mobot_cli.assets.world.pose import IDENTITY, Matrix
from mobot_cli.errors import Location


@dataclass
class Inertial:
    """A link's mass properties; ``pose`` is relative to the link (SDF defaults when absent)."""

    mass: float = 1.0
    pose: Matrix = field(default_factory=lambda: IDENTITY.copy())
    inertia: tuple[float, ...] = (1.0, 0.0, 0.0, 1.0, 0.0, 1.0)  # ixx ixy ixz iyy iyz izz
    given: bool = False


@dataclass
class Link:
    """A link; ``pose`` is in the top-level model's frame, shape poses are link-relative."""

    name: str  # scoped: "nested::link" for links of nested models
    pose: Matrix
    collisions: list[Shape]
    visuals: list[Shape]
    inertial: Inertial
    location: Location
    sensors: list = field(default_factory=list)  # (lxml <sensor>, its pose in the link frame)


@dataclass
class Joint:
    """A joint; ``pose`` (its frame) and ``axis`` are in the top-level model's frame."""

    name: str
    type: str
    parent: str
    child: str
    pose: Matrix
    axis: tuple[float, float, float]
    limits: tuple[float, float, float, float]  # lower, upper, effort, velocity
    dynamics: tuple[float, float]  # damping, friction
    location: Location
    spring: tuple[float, float] = (0.0, 0.0)  # <dynamics><spring_stiffness>, <spring_reference>

    @property
    def moves(self) -> bool:
        """Whether it lets its child move: not fixed, and not a revolute or prismatic joint whose
        limits are both zero (how Gazebo worlds anchor scenery to `world`, and osrf's turtlebot
        bolts its rack on)."""
        if self.type == "fixed":
            return False
        lower, upper = self.limits[:2]
        return not (self.type in ("revolute", "prismatic") and abs(lower) < 1e-9 and abs(upper) < 1e-9)


@dataclass
class Model:
    """A top-level model with its nested models flattened into it."""

    name: str
    pose: Matrix  # in the world
    links: list[Link] = field(default_factory=list)
    joints: list[Joint] = field(default_factory=list)
    plugins: list = field(default_factory=list)  # lxml <plugin> elements
    location: Location = field(default_factory=Location)
    dynamic_links: int = 0  # links not covered by any <static>true</static>

    @property
    def static(self) -> bool:
        """True when every link is static (a model without links counts as static)."""
        return self.dynamic_links == 0


@dataclass
class World:
    """What a world file holds that mobot simulates, plus what it ignored."""

    name: str
    models: list[Model]
    ignored: Counter
    max_step_size: float | None = None
    state_poses: int = 0
    actors: list = field(default_factory=list)  # MoverPlans of its <actor>s (assets/world/actors.py)
