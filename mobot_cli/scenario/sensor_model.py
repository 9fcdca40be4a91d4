"""The typed ``sensors:`` mapping of a robot: change, add or turn off sensors of its description.

Each key names a sensor of the description (its <sensor name>, its topic, or the topic's last
segment: ``scan``, ``imu``, ``points``) or, when none has it, adds one (``type`` and ``link``
needed; the key becomes its name and topic). ``false``, ``off`` or ``{enabled: false}`` turns
it off; ``true`` or ``on`` keeps it as described. Field names follow mobot's SensorSpec;
checks that need the description (the link exists, min below max after merging) are in
sensors.py.
"""

from __future__ import annotations

import math
import re
import unicodedata
from typing import Annotated, Any, Literal, Optional

from pydantic import AfterValidator, BaseModel, BeforeValidator, ConfigDict, Field, StrictBool, model_validator

from mobot_cli.assets.description.sensors import IMAGE_FORMATS, MAX_IMAGE_SIDE, MAX_SAMPLES
from mobot_cli.common.transforms import quat_from_rpy
from mobot_cli.errors import shown
from mobot_cli.scenario.limits import MAX_COORDINATE, MAX_RATE_HZ, Float, Int, NonNegativeFloat, Vector3

MAX_LABEL_LENGTH = 256  # a sensor key, topic, frame, link or collision name
KEY_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_.-]*(/[A-Za-z_][A-Za-z0-9_.-]*)*$")
TOPIC_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*$")
LIDAR_FIELDS = ("samples", "min_angle", "max_angle", "vertical_samples", "vertical_min_angle",
                "vertical_max_angle", "range_min", "range_max", "range_resolution")
CAMERA_FIELDS = ("width", "height", "image_format", "horizontal_fov", "clip_near", "clip_far")


def _label(value: str) -> str:
    if len(value) > MAX_LABEL_LENGTH:
        raise ValueError(f"{shown(value, 40)} is {len(value)} characters long, the limit is "
                         f"{MAX_LABEL_LENGTH}")
    if not value.strip() or any(unicodedata.category(c)[0] in "CZ" for c in value):
        raise ValueError(f"{shown(value, 40)} is empty or holds spaces or control characters")
    return value


def _topic(value: str) -> str:
    if not TOPIC_RE.match(value):
        raise ValueError(f"{shown(value, 40)} is not a relative ROS topic: use names of letters, "
                         "digits and '_' separated by '/', e.g. scan or front/scan (the robot's "
                         "namespace is put in front)")
    return value


def _key(value: str) -> str:
    if not KEY_RE.match(value):
        raise ValueError(f"sensor key {shown(value, 40)} is not a sensor's name or topic: use "
                         "letters, digits, '_', '-', '.' and '/'")
    return value


Label = Annotated[str, AfterValidator(_label)]
Topic = Annotated[Label, AfterValidator(_topic)]
SensorKey = Annotated[Label, AfterValidator(_key)]
Distance = Annotated[NonNegativeFloat, Field(le=MAX_COORDINATE)]


class SensorPose(BaseModel):
    """A sensor's pose in its link's frame: {xyz, rpy} or {xyz, quat: [x, y, z, w]}."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True, defer_build=True)

    xyz: Vector3 = (0.0, 0.0, 0.0)
    rpy: Optional[Vector3] = None
    quat: Optional[tuple[Float, Float, Float, Float]] = None

    @model_validator(mode="after")
    def _one_rotation(self) -> "SensorPose":
        if self.rpy is not None and self.quat is not None:
            raise ValueError("gives both 'rpy' and 'quat': use one")
        if self.quat is not None and math.sqrt(sum(q * q for q in self.quat)) < 1e-9:
            raise ValueError("quat has zero length: give [x, y, z, w], e.g. [0, 0, 0, 1]")
        if any(abs(v) > MAX_COORDINATE for v in self.xyz):
            raise ValueError(f"xyz is farther than {MAX_COORDINATE:g} m from its link")
        return self


def _switch(value: Any) -> Any:
    """false/off turn a sensor off, true/on keep it: both become the mapping form."""
    if value is False or value == "off":
        return {"enabled": False}
    if value is True or value == "on":
        return {}
    if not isinstance(value, dict):
        raise ValueError(f"{shown(value, 40)} is not a sensor's settings: give a mapping such as "
                         "{rate_hz: 10}, or false (off) to turn the sensor off")
    return value


# Hints for values the model refuses, by field name (load.py adds them to the error).
HINTS = {
    "samples": f"Give a whole number of rays from 1 to {MAX_SAMPLES}.",
    "vertical_samples": f"Give a whole number of rays from 1 to {MAX_SAMPLES} (1: a 2D scan).",
    "rate_hz": "Give readings per second: above 0 and at most physics.rate_hz.",
    "range_min": "Give a distance in metres, 0 or more.",
    "range_max": "Give the farthest distance it measures, in metres.",
    "range_resolution": "Give a distance in metres, 0 or more (0: ranges are not rounded).",
    "noise_stddev": "A standard deviation is 0 or more.",
    "accel_noise_stddev": "A standard deviation is 0 or more.",
    "type": "Use ray, gpu_ray, lidar, gpu_lidar, imu, contact, camera, depth_camera or rgbd_camera.",
    "width": f"Give a whole number of pixels from 1 to {MAX_IMAGE_SIDE}.",
    "height": f"Give a whole number of pixels from 1 to {MAX_IMAGE_SIDE}.",
    "horizontal_fov": "Give an angle in radians above 0 and below pi.",
    "clip_near": "Give a distance in metres above 0.",
    "clip_far": "Give a distance in metres beyond clip_near.",
    "image_format": "Use " + ", ".join(IMAGE_FORMATS) + ".",
}


class SensorOverride(BaseModel):
    """What a scenario says about one sensor; None everywhere means 'as described'."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True, defer_build=True)

    enabled: Optional[StrictBool] = None
    type: Optional[Literal["ray", "gpu_ray", "lidar", "gpu_lidar", "imu", "contact", "camera", "depth",
                           "depth_camera", "rgbd_camera", "rgbd"]] = None
    link: Optional[Label] = None
    rate_hz: Optional[Annotated[Float, Field(gt=0, le=MAX_RATE_HZ)]] = None
    pose: Optional[SensorPose] = None
    samples: Optional[Annotated[Int, Field(ge=1, le=MAX_SAMPLES)]] = None
    min_angle: Optional[Float] = None
    max_angle: Optional[Float] = None
    vertical_samples: Optional[Annotated[Int, Field(ge=1, le=MAX_SAMPLES)]] = None
    vertical_min_angle: Optional[Float] = None
    vertical_max_angle: Optional[Float] = None
    range_min: Optional[Distance] = None
    range_max: Optional[Annotated[Distance, Field(gt=0)]] = None
    range_resolution: Optional[Distance] = None
    noise_mean: Optional[Float] = None
    noise_stddev: Optional[NonNegativeFloat] = None
    accel_noise_stddev: Optional[NonNegativeFloat] = None
    collision: Optional[Label] = None
    topic: Optional[Topic] = None
    frame_id: Optional[Label] = None
    width: Optional[Annotated[Int, Field(ge=1, le=MAX_IMAGE_SIDE)]] = None  # cameras (docs/cameras.md)
    height: Optional[Annotated[Int, Field(ge=1, le=MAX_IMAGE_SIDE)]] = None
    image_format: Optional[Literal[tuple(IMAGE_FORMATS)]] = None  # type: ignore[valid-type]
    horizontal_fov: Optional[Annotated[Float, Field(gt=0, lt=math.pi)]] = None
    clip_near: Optional[Annotated[Distance, Field(gt=0)]] = None
    clip_far: Optional[Annotated[Distance, Field(gt=0)]] = None

    @model_validator(mode="after")
    def _off_alone(self) -> "SensorOverride":
        changed = [k for k in self.model_fields_set if k != "enabled"]
        if self.enabled is False and changed:
            raise ValueError(f"turns the sensor off and also sets '{sorted(changed)[0]}': "
                             "turn it off, or change it")
        return self

    def changes(self) -> dict[str, Any]:
        """The fields it sets, as DescribedSensor values (pose as xyz and quat)."""
        out = {k: v for k, v in self.model_dump(exclude={"enabled", "pose"}).items()
               if v is not None}
        if self.pose is not None:
            out["xyz"] = tuple(self.pose.xyz)
            quat = self.pose.quat or quat_from_rpy(*(self.pose.rpy or (0.0, 0.0, 0.0)))
            norm = math.sqrt(sum(q * q for q in quat))
            # Unit quaternions stay bit-for-bit, so a resolved scenario reloads to the same plan.
            out["quat"] = tuple(quat) if abs(norm - 1.0) < 1e-12 else tuple(q / norm for q in quat)
        return out


SensorEntry = Annotated[SensorOverride, BeforeValidator(_switch)]
