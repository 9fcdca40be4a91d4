"""A robot's sensors, read from its <gazebo reference="LINK"><sensor> blocks as Gazebo reads them.

Types ray, gpu_ray, lidar and gpu_lidar are lidars (2D with one vertical sample), unless a range
plugin reads them (gazebo_ros's ray sensor with output_type sensor_msgs/Range, gazebo_ros_range,
hector's sonar): then they are range sensors, as Gazebo classic's sonar is. imu and contact (a
bumper) are the others mobot simulates, with IMUs that are model plugins (plugin_sensors.py).
Cameras (docs/cameras.md): camera is RGB, depth_camera (gz) depth only, depth (Gazebo classic:
gazebo_ros_camera publishes its image and its depth; without a gazebo_ros plugin, gz-sim reads it
as a depth_camera and so does mobot) and rgbd_camera/rgbd both. GPS and the rest
of SDFormat's types are left out with one notice. SDF models reach
this module as URDF: model_to_urdf copies each link's sensors into such blocks, posed in the
URDF link frame. Absent elements take
SDFormat's defaults (sdf/1.6 sensor.sdf, lidar.sdf, imu.sdf, noise.sdf): update_rate 0 (every
physics step), 640 horizontal samples between angles 0 and 0, one vertical sample, range 0..0,
no noise. The topic and frame come from the sensor's plugin or gz-sim elements (sensor_xml.py).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, fields, replace
from pathlib import Path

from mobot_cli.assets.description.plugin_sensors import plugin_sensors
from mobot_cli.assets.description.sensor_xml import SensorXml
from mobot_cli.common.transforms import quat_from_rpy, quat_mul
from mobot_cli.errors import DescriptionError, Location, Notice, did_you_mean
from mobot_cli.plan import CAMERA_KINDS, RayAxis, SensorSpec

LIDAR_TYPES = ("ray", "gpu_ray", "lidar", "gpu_lidar")
CAMERA_TYPES = {"camera": "camera", "depth_camera": "depth", "depth": "rgbd", "rgbd_camera": "rgbd", "rgbd": "rgbd"}
KINDS = {**{t: "lidar" for t in LIDAR_TYPES}, "sonar": "range", "imu": "imu", "contact": "contact",
         **CAMERA_TYPES}
RAY_KINDS = ("lidar", "range")  # sensors that cast rays: scan axes and a range
# SDFormat's other sensor types (sdf/1.9 sensor.sdf): real, but not simulated by mobot.
OTHER_TYPES = ("air_pressure", "air_speed", "altimeter", "boundingbox_camera", "boundingbox",
               "custom", "dvl", "force_torque", "gps",
               "logical_camera", "magnetometer", "multicamera", "navsat", "rfid", "rfidtag",
               "segmentation_camera", "segmentation",
               "thermal_camera", "thermal", "wide_angle_camera", "wireless_receiver",
               "wireless_transmitter")
SONAR_TURN = quat_from_rpy(0.0, math.pi / 2, 0.0)  # x onto -z: along a Gazebo sonar's cone
OTHER_TYPES += ("wideanglecamera",)  # Gazebo classic's spelling, which sdformat reads (turtlebot3_burger_cam)
MAX_SAMPLES = 100_000  # rays along one axis of a scan
MAX_RAYS = 1_000_000  # rays in one reading (horizontal x vertical samples)
# SDFormat's camera.sdf defaults, which a camera added in a scenario's sensors: starts from
CAMERA_DEFAULTS = dict(width=320, height=240, image_format="R8G8B8", horizontal_fov=1.047, clip_near=0.1,
                       clip_far=100.0)
MAX_IMAGE_SIDE = 4096  # pixels along one side of a camera's image
# <image><format> -> the sensor_msgs/Image encoding mobot renders (others: rgb8, with a notice)
IMAGE_FORMATS = {"R8G8B8": "rgb8", "RGB_INT8": "rgb8", "B8G8R8": "bgr8", "BGR_INT8": "bgr8",
                 "L8": "mono8", "L_INT8": "mono8", "R_FLOAT32": "rgb8", "FLOAT32": "rgb8"}


@dataclass(frozen=True)
class DescribedSensor:
    """One sensor with every value resolved but its rate, which becomes steps in a plan.

    Field names are the scenario's ``sensors:`` keys, so overrides replace them one for one.
    """

    name: str  # the <sensor name>
    type: str  # Gazebo's type as written: ray, gpu_lidar, imu, contact, ...
    link: str
    rate_hz: float = 0.0  # 0: every physics step, as Gazebo does without <update_rate>
    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    quat: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0)
    samples: int = 640
    min_angle: float = 0.0
    max_angle: float = 0.0
    resolution: float = 1.0
    vertical_samples: int = 1
    vertical_min_angle: float = 0.0
    vertical_max_angle: float = 0.0
    vertical_resolution: float = 1.0
    range_min: float = 0.0
    range_max: float = 0.0
    range_resolution: float = 0.0
    noise_mean: float = 0.0
    noise_stddev: float = 0.0
    accel_noise_stddev: float = 0.0
    collision: str = ""
    topic: str = ""
    frame_id: str = ""  # "" when the block names none: the link's name
    radiation: str = ""  # a range sensor's "ultrasound" or "infrared"; "" for every other kind
    field_of_view: float = 0.0  # rad, a range sensor's, as its plugin reports it
    reading_noise_stddev: float = 0.0  # m, a range plugin's gaussian noise on the reading
    width: int = 0  # cameras: image size in pixels
    height: int = 0
    image_format: str = ""  # cameras: <image><format> as written (R8G8B8, L8, ...)
    horizontal_fov: float = 0.0  # rad, cameras
    clip_near: float = 0.0  # m, cameras
    clip_far: float = 0.0
    depth_near: float = 0.0  # m, depth cameras' <depth_camera><clip> (0 and 0: none)
    depth_far: float = 0.0

    @property
    def kind(self) -> str:
        """"lidar", "range", "imu" or "contact"."""
        return "range" if self.radiation else KINDS[self.type]

    def spec(self, every: int, source: str = "") -> SensorSpec:
        """The plan's form, reading every ``every`` physics steps."""
        lidar = self.kind in RAY_KINDS
        if self.kind in CAMERA_KINDS:
            return SensorSpec(
                name=self.name, kind=self.kind, link=self.link, every=every, xyz=self.xyz, quat=self.quat,
                topic=self.topic, frame_id=self.frame_id or self.link, range_min=self.clip_near,
                range_max=self.clip_far, noise_mean=self.noise_mean, noise_stddev=self.noise_stddev, source=source,
                field_of_view=self.horizontal_fov, width=self.width, height=self.height,
                encoding=IMAGE_FORMATS.get(self.image_format, "rgb8"),
                depth_clip=(self.depth_near, self.depth_far) if self.depth_far > 0.0 and self.kind != "camera"
                else None)
        return SensorSpec(
            name=self.name, kind=self.kind, link=self.link, every=every, xyz=self.xyz,
            quat=self.quat, topic=self.topic, frame_id=self.frame_id or self.link,
            horizontal=RayAxis(self.samples, self.min_angle, self.max_angle, self.resolution)
            if lidar else None,
            vertical=RayAxis(self.vertical_samples, self.vertical_min_angle,
                             self.vertical_max_angle, self.vertical_resolution) if lidar else None,
            range_min=self.range_min if lidar else 0.0, range_max=self.range_max if lidar else 0.0,
            range_resolution=self.range_resolution if lidar else 0.0,
            noise_mean=self.noise_mean, noise_stddev=self.noise_stddev,
            accel_noise_stddev=self.accel_noise_stddev, collision=self.collision, source=source,
            radiation=self.radiation, field_of_view=self.field_of_view,
            reading_noise_stddev=self.reading_noise_stddev)


SENSOR_FIELDS = tuple(f.name for f in fields(DescribedSensor))


def sensor_summary(sensor: DescribedSensor) -> dict:
    """A sensor as `mobot inspect --json` shows it: the fields its kind uses."""
    lidar = ("samples", "min_angle", "max_angle", "resolution", "vertical_samples",
             "vertical_min_angle", "vertical_max_angle", "vertical_resolution", "range_min",
             "range_max", "range_resolution", "noise_mean", "noise_stddev")
    ranged = (*lidar, "radiation", "field_of_view", "reading_noise_stddev")
    own = {"lidar": lidar, "range": ranged, "imu": ("noise_mean", "noise_stddev", "accel_noise_stddev"),
           "contact": ("collision",)}.get(sensor.kind) or CAMERA_FIELDS
    out = {"name": sensor.name, "type": sensor.type, "kind": sensor.kind, "link": sensor.link,
           "topic": sensor.topic, "frame_id": sensor.frame_id or sensor.link,
           "rate_hz": sensor.rate_hz, "xyz": list(sensor.xyz), "quat": list(sensor.quat)}
    return {**out, **{name: getattr(sensor, name) for name in own}}


CAMERA_FIELDS = ("width", "height", "image_format", "horizontal_fov", "clip_near", "clip_far", "noise_mean",
                 "noise_stddev")


def read_sensors(robot: ET.Element, source: Path,
                 notices: list[Notice]) -> tuple[DescribedSensor, ...]:
    """Every simulated sensor of an expanded URDF, checked; others skipped with one notice."""
    links = {link.get("name", ""): link for link in robot.findall("link")}
    found: list[DescribedSensor] = []
    skipped: list[str] = []
    for gazebo in robot.findall("gazebo"):
        for element in gazebo.findall("sensor"):
            xml = SensorXml(element, gazebo.get("reference", "").strip(), source, notices)
            if xml.type in OTHER_TYPES:
                skipped.append(f"{xml.type} '{xml.name}'")
                continue
            _check_placement(xml, links, found)
            found.append(_read(xml))
    for values in plugin_sensors(robot, source, skipped, notices):
        sensor = DescribedSensor(**values)
        if any(s.kind == "imu" and (s.link == sensor.link or (s.topic or default_topic(s)) == sensor.topic)
               for s in found):
            continue  # the same IMU as a <sensor> (turtlebot3 has both): the <sensor> is read
        if any(s.name == sensor.name for s in found) or sensor.link not in links:
            why = "no link" if sensor.link not in links else "the name of another sensor"
            skipped.append(f"IMU plugin '{sensor.name}' ({why} '{sensor.link if why == 'no link' else sensor.name}')")
            continue
        found.append(sensor)
    if skipped:
        notices.append(Notice("sensors of types mobot does not simulate are left out: "
                              + ", ".join(skipped), Location(file=source)))
    checked = []
    for sensor in default_topics(found):
        collisions = collision_names(links[sensor.link])
        problem = check_values(sensor, collisions)
        if problem is not None:
            field, message, hint = problem
            raise DescriptionError(f"sensor '{sensor.name}' {message}", location=Location(
                file=source, key=f"gazebo.sensor.{sensor.name}.{XML_KEYS.get(field, field)}"),
                hint=hint.replace("{field}", XML_NAMES.get(field, field)))
        checked.append(with_gazebo_collision(sensor, collisions))
    coarse = [f"{s.name} ({s.range_resolution:g} m over {s.range_min:g}..{s.range_max:g} m)" for s in checked
              if s.kind in RAY_KINDS and s.range_resolution >= s.range_max - s.range_min > 0]
    if coarse:  # create3's cliff and IR sensors: every return reads range_min or range_max
        notices.append(Notice("sensors round ranges to a resolution no finer than their span, so every return "
                              f"reads one of their limits: {', '.join(coarse)}", Location(file=source)))
    return tuple(checked)


def with_gazebo_collision(sensor: DescribedSensor, collisions: tuple[str, ...]) -> DescribedSensor:
    """A checked contact sensor names its collision as Gazebo does (LINK_collision, ...)."""
    if sensor.kind != "contact":
        return sensor
    return replace(sensor, collision=contact_collision(sensor.collision, collisions) or "")


def default_topic(sensor: DescribedSensor) -> str:
    """The topic of a sensor whose block names none: scan, points (3D), imu or bumper."""
    if sensor.kind == "lidar":
        return "scan" if sensor.vertical_samples <= 1 else "points"
    if sensor.kind in CAMERA_KINDS:
        return "camera"
    return {"range": "range", "contact": "bumper"}.get(sensor.kind, "imu")


def default_topics(sensors: list[DescribedSensor]) -> list[DescribedSensor]:
    """Give sensors without a topic their kind's usual one, or their name when it is taken."""
    taken = {s.topic for s in sensors if s.topic}
    out = []
    for sensor in sensors:
        if not sensor.topic:
            topic = default_topic(sensor)
            topic = sensor.name if topic in taken else topic
            taken.add(topic)
            sensor = replace(sensor, topic=topic)
        out.append(sensor)
    return out


def _check_placement(xml: SensorXml, links: dict[str, ET.Element],
                     found: list[DescribedSensor]) -> None:
    where = xml.location()
    if not xml.name:
        raise DescriptionError(f"a <sensor> of type '{xml.type}' has no name", location=where,
                               hint="Give it name=\"...\", unique within the robot.")
    if xml.type not in KINDS:
        raise DescriptionError(
            f"sensor '{xml.name}' has unknown type '{xml.type}'", location=where,
            hint=did_you_mean(xml.type, [*KINDS, *OTHER_TYPES]) or "Use ray, lidar, imu or contact.")
    if not xml.link:
        raise DescriptionError(f"sensor '{xml.name}' is in a <gazebo> block without a reference",
                               location=where, hint="Put it in <gazebo reference=\"LINK\">.")
    if xml.link not in links:
        raise DescriptionError(f"sensor '{xml.name}' is on link '{xml.link}', which the robot "
                               "does not have", location=where,
                               hint=did_you_mean(xml.link, links) or "Name one of its links.")
    twin = next((s for s in found if s.name == xml.name), None)
    if twin is not None:
        raise DescriptionError(f"two sensors are named '{xml.name}' (on links '{twin.link}' and "
                               f"'{xml.link}')", location=where,
                               hint="Give every sensor of a robot its own name.")


def _read(xml: SensorXml) -> DescribedSensor:
    values = dict(name=xml.name, type=xml.type, link=xml.link,
                  rate_hz=xml.number("update_rate", 0.0), topic=xml.topic(), frame_id=xml.frame())
    values["xyz"], values["quat"] = xml.pose()
    kind = KINDS[xml.type]
    if kind == "lidar":
        values.update(xml.lidar())
        values.update(xml.range_plugin(values) or {})
    elif kind == "range":  # Gazebo classic's sonar: a cone, x turned along it
        values.update(xml.sonar())
        values["quat"] = quat_mul(values["quat"], SONAR_TURN)
    elif kind == "imu":
        values.update(xml.imu())
    elif kind in CAMERA_KINDS:
        values.update(xml.camera())
        if values["image_format"] not in IMAGE_FORMATS:
            xml.notices.append(Notice(f"sensor '{xml.name}' has <format> '{values['image_format'][:40]}': "
                                      "mobot renders it as rgb8", xml.location("camera/image/format")))
    else:
        values["collision"] = xml.text("contact/collision")
    return DescribedSensor(**values)


def collision_names(link: ET.Element) -> tuple[str, ...]:
    """Gazebo's names for a URDF link's collisions: NAME_collision, then NAME_collision_1, ...

    NAME is the <collision name> or else the link's name (sdformat's parser_urdf.cc).
    """
    out = []
    for index, collision in enumerate(link.findall("collision")):
        name = (collision.get("name") or link.get("name", "")) + "_collision"
        out.append(name if index == 0 else f"{name}_{index}")
    return tuple(out)


def contact_collision(wanted: str, names: tuple[str, ...]) -> str | None:
    """The Gazebo name of the collision ``wanted`` names ("" = the whole link), or None.

    Accepted: Gazebo's name (LINK_collision, NAME_collision_1), the <collision name> as
    written (NAME), and Gazebo's fixed-joint-lumped form (PARENT_fixed_joint_lump__NAME...).
    """
    if wanted in ("", "__default__"):
        return ""
    for candidate in dict.fromkeys((wanted, wanted.split("_fixed_joint_lump__")[-1])):
        if candidate in names:
            return candidate
        written = [n for n in names if n == f"{candidate}_collision"
                   or n.startswith(f"{candidate}_collision_")]
        if len(written) == 1:
            return written[0]
    return None


# Where each field lives in a <sensor> block, for messages about a description.
XML_KEYS = {
    "rate_hz": "update_rate", "samples": "ray.scan.horizontal.samples",
    "min_angle": "ray.scan.horizontal.min_angle", "max_angle": "ray.scan.horizontal.max_angle",
    "resolution": "ray.scan.horizontal.resolution", "vertical_samples": "ray.scan.vertical.samples",
    "vertical_min_angle": "ray.scan.vertical.min_angle",
    "vertical_max_angle": "ray.scan.vertical.max_angle",
    "vertical_resolution": "ray.scan.vertical.resolution", "range_min": "ray.range.min",
    "range_max": "ray.range.max", "range_resolution": "ray.range.resolution",
    "noise_stddev": "noise.stddev", "accel_noise_stddev": "imu.linear_acceleration.noise.stddev",
    "collision": "contact.collision", "reading_noise_stddev": "plugin.gaussianNoise",
    "width": "camera.image.width", "height": "camera.image.height", "horizontal_fov": "camera.horizontal_fov",
    "clip_near": "camera.clip.near", "clip_far": "camera.clip.far"}
XML_NAMES = {"rate_hz": "<update_rate>", "samples": "<horizontal><samples>",
             "min_angle": "<horizontal><min_angle>", "max_angle": "<horizontal><max_angle>",
             "resolution": "<horizontal><resolution>", "vertical_samples": "<vertical><samples>",
             "vertical_min_angle": "<vertical><min_angle>",
             "vertical_max_angle": "<vertical><max_angle>",
             "vertical_resolution": "<vertical><resolution>", "range_min": "<range><min>",
             "range_max": "<range><max>", "range_resolution": "<range><resolution>",
             "noise_stddev": "<noise><stddev>", "accel_noise_stddev": "the accelerometer's <stddev>",
             "collision": "<contact><collision>", "reading_noise_stddev": "the plugin's <gaussianNoise>",
             "width": "<image><width>", "height": "<image><height>", "horizontal_fov": "<horizontal_fov>",
             "clip_near": "<clip><near>", "clip_far": "<clip><far>"}


def check_values(sensor: DescribedSensor,
                 collisions: tuple[str, ...]) -> tuple[str, str, str] | None:
    """The first problem as (field, message, hint with a {field} slot), or None when sound."""
    for name in SENSOR_FIELDS:
        value = getattr(sensor, name)
        if isinstance(value, float) and not math.isfinite(value):
            return name, f"has a non-finite {name} ({value})", "Give {field} a finite number."
    if sensor.rate_hz < 0:
        return "rate_hz", f"has a negative rate ({sensor.rate_hz:g} Hz)", \
            "Give {field} a rate in Hz (0: every physics step)."
    if sensor.noise_stddev < 0 or sensor.accel_noise_stddev < 0:
        field = "noise_stddev" if sensor.noise_stddev < 0 else "accel_noise_stddev"
        return field, f"has a negative noise standard deviation ({getattr(sensor, field):g})", \
            "Give {field} a value of 0 or more."
    if sensor.reading_noise_stddev < 0:
        return "reading_noise_stddev", "has a negative noise standard deviation " \
            f"({sensor.reading_noise_stddev:g})", "Give {field} a value of 0 or more."
    if sensor.kind in RAY_KINDS:
        return _check_lidar(sensor)
    if sensor.kind in CAMERA_KINDS:
        return _check_camera(sensor)
    if sensor.kind == "contact" and contact_collision(sensor.collision, collisions) is None:
        return "collision", f"counts contacts of collision '{sensor.collision}', which link " \
            f"'{sensor.link}' does not have", (did_you_mean(sensor.collision, collisions)
                                               or "Name one of the link's collisions.") + \
            " Gazebo names a link's collisions LINK_collision, LINK_collision_1, ..."
    return None


def _check_lidar(s: DescribedSensor) -> tuple[str, str, str] | None:
    for prefix, label in (("", "horizontal"), ("vertical_", "vertical")):
        samples = getattr(s, prefix + "samples")
        low, high = getattr(s, prefix + "min_angle"), getattr(s, prefix + "max_angle")
        if not 1 <= samples <= MAX_SAMPLES:
            return prefix + "samples", f"has {samples} {label} samples", \
                f"Give {{field}} a whole number from 1 to {MAX_SAMPLES}."
        if getattr(s, prefix + "resolution") <= 0:
            return prefix + "resolution", f"has a {label} resolution of " \
                f"{getattr(s, prefix + 'resolution'):g}", "Give {field} a number above 0."
        if low > high or (low == high and samples > 1):
            return prefix + "max_angle", f"has {label} angles from {low:g} to {high:g} rad", \
                "Make {field} greater than the min angle (equal only with one sample)."
    if s.samples * s.vertical_samples > MAX_RAYS:
        return "samples", f"casts {s.samples} x {s.vertical_samples} rays per reading", \
            f"Keep a reading at or below {MAX_RAYS} rays."
    if s.range_min < 0:
        return "range_min", f"has a negative range min ({s.range_min:g} m)", \
            "Give {field} a distance of 0 or more."
    if s.range_max <= s.range_min:
        return "range_max", f"has range max {s.range_max:g} m, not beyond its range min " \
            f"{s.range_min:g} m", "Give {field} the farthest distance it measures."
    if s.range_resolution < 0:
        return "range_resolution", f"has a negative range resolution ({s.range_resolution:g})", \
            "Give {field} a distance of 0 or more (0: not quantised)."
    return None


def _check_camera(s: DescribedSensor) -> tuple[str, str, str] | None:
    for side in ("width", "height"):
        if not 1 <= getattr(s, side) <= MAX_IMAGE_SIDE:
            return side, f"has an image {side} of {getattr(s, side)} pixels", \
                f"Give {{field}} a whole number of pixels from 1 to {MAX_IMAGE_SIDE}."
    if not 0.0 < s.horizontal_fov < math.pi:
        return "horizontal_fov", f"has a horizontal field of view of {s.horizontal_fov:g} rad", \
            "Give {field} an angle above 0 and below pi (a pinhole camera sees less than 180 degrees)."
    if s.clip_near <= 0:
        return "clip_near", f"has a near clip of {s.clip_near:g} m", "Give {field} a distance above 0."
    if s.clip_far <= s.clip_near:
        return "clip_far", f"has far clip {s.clip_far:g} m, not beyond its near clip {s.clip_near:g} m", \
            "Give {field} the farthest distance it sees."
    return None
