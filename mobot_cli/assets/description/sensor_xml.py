"""The values of one <sensor> element: numbers with SDFormat's defaults, pose, noise, topic, frame.

Topic, first found: a gazebo_ros (ROS 2) plugin's ``<ros><remapping>~/out:=scan``; a ROS 1
plugin's ``<topicName>`` (``<bumperTopicName>``); gz-sim's ``<topic>`` in the sensor (or in its
``<contact>``/``<imu>``); a gazebo_ros plugin without a remapping publishes ``~/out``, i.e.
``PLUGIN_NAME/out``. Topics are relative to the robot's namespace: a leading '/' is dropped and a
plugin's ``<namespace>`` is replaced by the robot's, as ``spawn_entity.py -robot_namespace`` does.
Frame: the plugin's ``<frame_name>`` (``<frameName>``), gz-sim's ``<gz_frame_id>``, else the link.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

from mobot_cli.assets.lenient import sdf_integer
from mobot_cli.common.transforms import quat_from_rpy
from mobot_cli.errors import DescriptionError, Location, Notice

_UNSET = ("", "__default__", "__default_topic__")


class SensorXml:
    """One <sensor> element on ``link``, read with located errors."""

    def __init__(self, element: ET.Element, link: str, source: Path, notices: list[Notice] | None = None):
        self.element, self.link, self.source = element, link, source
        self.notices = notices if notices is not None else []  # values read as sdformat reads them
        self.name = element.get("name", "").strip()
        self.type = element.get("type", "").strip()
        self.plugin = element.find("plugin")

    def location(self, path: str = "") -> Location:
        """The description file and a key naming this sensor (and ``path`` inside it)."""
        key = f"gazebo.sensor.{self.name or self.type or '?'}"
        return Location(file=self.source, key=key + ("." + path.replace("/", ".") if path else ""))

    def text(self, path: str) -> str:
        """The stripped text at ``path``; "" when absent."""
        return (self.element.findtext(path) or "").strip()

    def number(self, path: str, default: float) -> float:
        """A finite number at ``path``, or ``default`` when absent or empty."""
        text = self.text(path)
        if not text:
            return default
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        if not math.isfinite(value):
            raise DescriptionError(f"sensor '{self.name}' has <{path.split('/')[-1]}> "
                                   f"'{text[:40]}', which is not a finite number",
                                   location=self.location(path), hint="Write a plain number.")
        return value

    def integer(self, path: str, default: int) -> int:
        """A whole number at ``path`` (SDF's unsigned int), or ``default``; read as sdformat reads
        it (666.519 is 666, with a notice), as an xacro expression often gives a fraction."""
        text = self.text(path)
        if not text:
            return default
        self.number(path, float(default))  # text that is no number at all is an error
        read = sdf_integer(text)
        if read is None:
            raise DescriptionError(f"sensor '{self.name}' has <{path.split('/')[-1]}> '{text[:40]}', "
                                   "which is not a whole number", location=self.location(path),
                                   hint="Give a whole number of samples.")
        value, rest = read
        if rest:
            self.notices.append(Notice(f"sensor '{self.name}' has <{path.split('/')[-1]}> '{text[:40]}': "
                                       f"read as {value}, as Gazebo (sdformat) reads a whole number",
                                       self.location(path)))
        return value

    def pose(self) -> tuple[tuple[float, float, float], tuple[float, float, float, float]]:
        """The sensor's <pose> in its link's frame: 'x y z roll pitch yaw' (or a quaternion)."""
        element = self.element.find("pose")
        parts = (element.text or "").split() if element is not None else []
        if not parts:
            return (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0)
        quat = element.get("rotation_format", "") == "quat_xyzw"  # type: ignore[union-attr]
        try:
            values = [float(p) for p in parts]
        except ValueError:
            values = []
        if len(values) != (7 if quat else 6) or not all(math.isfinite(v) for v in values):
            raise DescriptionError(f"sensor '{self.name}' has <pose> '{' '.join(parts)[:60]}'",
                                   location=self.location("pose"),
                                   hint="A pose is 'x y z roll pitch yaw' in metres and radians.")
        xyz = (values[0], values[1], values[2])
        if quat:
            norm = math.sqrt(sum(v * v for v in values[3:])) or 1.0
            return xyz, tuple(v / norm for v in values[3:])  # type: ignore[return-value]
        angles = values[3:]
        if element.get("degrees", "").strip().lower() in ("true", "1"):  # type: ignore[union-attr]
            angles = [math.radians(a) for a in angles]
        return xyz, quat_from_rpy(*angles)

    def lidar(self) -> dict:
        """Scan axes, range and noise of a ray/lidar sensor (<ray> or <lidar>)."""
        tag = "lidar" if self.element.find("lidar") is not None else "ray"
        h, v, r = f"{tag}/scan/horizontal", f"{tag}/scan/vertical", f"{tag}/range"
        mean, stddev = self.noise(f"{tag}/noise", "gaussian")
        values = dict(
            samples=self.integer(f"{h}/samples", 640), resolution=self.number(f"{h}/resolution", 1.0),
            min_angle=self.number(f"{h}/min_angle", 0.0), max_angle=self.number(f"{h}/max_angle", 0.0),
            vertical_samples=self.integer(f"{v}/samples", 1),
            vertical_resolution=self.number(f"{v}/resolution", 1.0),
            vertical_min_angle=self.number(f"{v}/min_angle", 0.0),
            vertical_max_angle=self.number(f"{v}/max_angle", 0.0),
            range_min=self.number(f"{r}/min", 0.0), range_max=self.number(f"{r}/max", 0.0),
            range_resolution=self.number(f"{r}/resolution", 0.0), noise_mean=mean, noise_stddev=stddev)
        plugin = self.plugin
        if plugin is not None and "velodyne" in plugin.get("filename", "").lower():
            # velodyne_gazebo_plugins drops points outside its own range and adds its own noise.
            low, high = _plugin_number(plugin, "min_range"), _plugin_number(plugin, "max_range")
            extra = _plugin_number(plugin, "gaussianNoise") or 0.0
            values["range_min"] = max(values["range_min"], low if low is not None else -math.inf)
            values["range_max"] = min(values["range_max"], high if high is not None else math.inf)
            values["noise_stddev"] = math.hypot(stddev, extra)
        return values

    def imu(self) -> dict:
        """Gyro noise (the noisiest axis) and accelerometer noise of an imu sensor."""
        gyro = [self.noise(f"imu/angular_velocity/{a}/noise", "none") for a in "xyz"]
        accel = [self.noise(f"imu/linear_acceleration/{a}/noise", "none") for a in "xyz"]
        old = self.element.find("imu/noise")  # SDF 1.4's form: <noise><type/><rate/><accel/>
        if old is not None and (old.get("type") or self.text("imu/noise/type")) != "none":
            gyro.append((self.number("imu/noise/rate/mean", 0.0),
                         self.number("imu/noise/rate/stddev", 0.0)))
            accel.append((0.0, self.number("imu/noise/accel/stddev", 0.0)))
        # One value for all axes: the noisiest (by magnitude, so a negative one is reported).
        mean, stddev = max(gyro, key=lambda n: abs(n[1]))
        return dict(noise_mean=mean, noise_stddev=stddev,
                    accel_noise_stddev=max((a[1] for a in accel), key=abs))

    def noise(self, path: str, default_type: str) -> tuple[float, float]:
        """(mean, stddev) of a <noise> block; zeros when absent or of type none."""
        element = self.element.find(path)
        if element is None:
            return 0.0, 0.0
        kind = (element.get("type") or element.findtext("type") or default_type).strip()
        if kind == "none":
            return 0.0, 0.0
        return self.number(f"{path}/mean", 0.0), self.number(f"{path}/stddev", 0.0)

    def topic(self) -> str:
        """The topic the sensor publishes on, relative to the robot's namespace ("" = default)."""
        plugin = self.plugin
        if plugin is not None:
            for tag in ("ros/remapping", "ros/argument", "remapping"):
                for element in plugin.findall(tag):
                    text = (element.text or "").strip()
                    if ":=" in text and clean_topic(text.split(":=", 1)[1]):
                        return clean_topic(text.split(":=", 1)[1])
            for tag in ("topicName", "topic_name", "bumperTopicName", "topic"):
                text = (plugin.findtext(tag) or "").strip()
                if text not in _UNSET and clean_topic(text):
                    return clean_topic(text)
        for path in ("topic", "contact/topic", "imu/topic"):
            text = self.text(path)
            if text not in _UNSET and clean_topic(text):
                return clean_topic(text)
        if plugin is not None and plugin.find("ros") is not None:
            return clean_topic(f"{plugin.get('name', '').strip()}/out")
        return ""

    def frame(self) -> str:
        """The frame readings are stamped with, when the block names one."""
        if self.plugin is not None:
            for tag in ("frame_name", "frameName"):
                text = (self.plugin.findtext(tag) or "").strip()
                if text:
                    return text
        for tag in ("gz_frame_id", "ignition_frame_id", "frame_id"):
            if self.text(tag):
                return self.text(tag)
        return ""


def clean_topic(text: str) -> str:
    """A topic relative to the robot's namespace: no '~/', no leading or trailing '/'."""
    text = text.strip().removeprefix("~")
    return "/".join(part for part in text.split("/") if part)


def _plugin_number(plugin: ET.Element, tag: str) -> float | None:
    try:
        value = float((plugin.findtext(tag) or "").strip())
    except ValueError:
        return None
    return value if math.isfinite(value) else None
