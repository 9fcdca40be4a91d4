"""The values of one <sensor> element: numbers with SDFormat's defaults, pose, noise, topic, frame.

Topic, first found: a gazebo_ros (ROS 2) plugin's ``<ros><remapping>~/out:=scan``; a ROS 1
plugin's ``<topicName>`` (``<bumperTopicName>``); gz-sim's ``<topic>`` in the sensor (or in its
``<contact>``/``<imu>``); a gazebo_ros plugin without a remapping publishes ``~/out``, i.e.
``PLUGIN_NAME/out``. Topics are relative to the robot's namespace: a leading '/' is dropped and a
plugin's ``<namespace>`` is replaced by the robot's, as ``spawn_entity.py -robot_namespace`` does.
Frame: the plugin's ``<frame_name>`` (``<frameName>``), gz-sim's ``<gz_frame_id>``, else the link.

Range plugins make a ray sensor a range sensor (``range_plugin``): gazebo_ros's ray sensor with
``<output_type>sensor_msgs/Range</output_type>`` (ROS 2), gazebo_ros_range (ROS 1) and hector's
sonar plugin, each with its own radiation type, field of view and noise.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

from mobot_cli.assets.lenient import sdf_integer
from mobot_cli.common.transforms import quat_from_rpy
from mobot_cli.errors import DescriptionError, Location, Notice

_UNSET = ("", "__default__", "__default_topic__")
SONAR_RAYS = 9  # rays along each axis of a sonar's cone


class SensorXml:
    """One <sensor> element on ``link``, read with located errors."""

    def __init__(self, element: ET.Element, link: str, source: Path, notices: list[Notice] | None = None):
        self.element, self.link, self.source = element, link, source
        self.notices = notices if notices is not None else []  # values read as sdformat reads them
        self.name = element.get("name", "").strip()
        self.type = element.get("type", "").strip()
        plugins = element.findall("plugin")
        # A range plugin decides what the sensor is (and names its topic and frame)
        self.plugin = next((p for p in plugins if _range_plugin(p)), plugins[0] if plugins else None)

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
        return finite(text, f"sensor '{self.name}'", path.split("/")[-1], self.location(path))

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

    def range_plugin(self, axes: dict) -> dict | None:
        """Radiation, field of view and reading noise of a ray sensor's range plugin, as each
        plugin fills sensor_msgs/Range; None when no plugin makes it a range sensor. ``axes``
        are its ``lidar()`` values (field of view from the scan's angles)."""
        wide = axes["max_angle"] - axes["min_angle"]
        high = axes["vertical_max_angle"] - axes["vertical_min_angle"]
        plugin = self.plugin
        if plugin is not None and _range_plugin(plugin):
            filename = plugin.get("filename", "").lower()
            if _range_output(plugin):
                # gazebo_ros_ray_sensor (ROS 2): <radiation_type>, default infrared; the wider
                # axis as field of view; no noise of its own (the <ray> block's is on each ray)
                kind = (plugin.findtext("radiation_type") or "infrared").strip()
                if kind not in ("ultrasound", "infrared"):
                    raise DescriptionError(
                        f"sensor '{self.name}' has <radiation_type> '{kind[:40]}'",
                        location=self.location("plugin/radiation_type"),
                        hint="gazebo_ros reads ultrasound or infrared (and loads no plugin otherwise).")
                return dict(radiation=kind, field_of_view=max(wide, high), reading_noise_stddev=0.0)
            if "gazebo_ros_range" in filename:  # ROS 1: <radiation> (anything else is infrared), <fov>
                kind = (plugin.findtext("radiation") or "ultrasound").strip()
                return dict(radiation="ultrasound" if kind == "ultrasound" else "infrared",
                            field_of_view=self.plugin_number("fov", 0.05),
                            reading_noise_stddev=abs(self.plugin_number("gaussianNoise", 0.0)))
            if "sonar" in filename:  # hector_gazebo_ros_sonar: the narrower axis as field of view
                return dict(radiation="ultrasound", field_of_view=min(abs(wide), abs(high)),
                            reading_noise_stddev=abs(self.plugin_number("gaussianNoise", 0.0)))
        return None

    def sonar(self) -> dict:
        """A Gazebo classic ``sonar`` sensor (<sonar><min>, <max>, <radius>) as a range sensor: a
        cone along the sensor's -z axis from its apex at the sensor, ``radius`` wide at
        ``max - min``, swept by SONAR_RAYS x SONAR_RAYS rays (the pose is turned so that x
        points along the cone, as a Range message's frame does)."""
        low, high = self.number("sonar/min", 0.0), self.number("sonar/max", 1.0)
        radius = self.number("sonar/radius", 0.5)
        if radius < 0 or low < 0 or high <= low:
            raise DescriptionError(f"sensor '{self.name}' has <sonar> min {low:g}, max {high:g}, "
                                   f"radius {radius:g}", location=self.location("sonar"),
                                   hint="Give 0 <= min < max and a radius of 0 or more.")
        half = math.atan2(radius, high - low)
        samples = SONAR_RAYS if half > 0 else 1
        # a ROS plugin on it (gazebo_plugins_sonar and the like) may add noise and report its <fov>
        return dict(samples=samples, min_angle=-half, max_angle=half, vertical_samples=samples,
                    vertical_min_angle=-half, vertical_max_angle=half, range_min=low, range_max=high,
                    radiation="ultrasound", field_of_view=self.plugin_number("fov", 2 * half),
                    reading_noise_stddev=abs(self.plugin_number("gaussianNoise", 0.0)))

    def camera(self) -> dict:
        """Image size, format, horizontal field of view, clip planes and noise of a camera
        (``<camera>``), with SDFormat's defaults (camera.sdf: 320 x 240 R8G8B8, 1.047 rad,
        clip 0.1 .. 100 m); the topic is its plugin's ``<camera_name>`` (gazebo_ros publishes
        ``CAMERA_NAME/image_raw``), gz's ``<topic>`` (without a last ``/image_raw``: the images
        go there), else the sensor's name. Without ``<update_rate>``, a ROS 1 plugin's
        ``<updateRate>`` sets the rate, as gazebo_ros_openni_kinect and gazebo_ros_camera do.
        Without a Gazebo classic ROS plugin the sensor is read as gz-sim reads it: a ``depth``
        sensor is a depth camera, and ``<depth_camera><clip>`` bounds its depth image."""
        mean, stddev = self.noise("camera/noise", "gaussian")
        values = dict(width=self.integer("camera/image/width", 320), height=self.integer("camera/image/height", 240),
                      image_format=self.text("camera/image/format") or "R8G8B8",
                      horizontal_fov=self.number("camera/horizontal_fov", 1.047),
                      clip_near=self.number("camera/clip/near", 0.1), clip_far=self.number("camera/clip/far", 100.0),
                      noise_mean=mean, noise_stddev=stddev)
        if self.plugin is None or not _gazebo_ros_plugin(self.plugin):  # gz-sim reads the sensor
            if self.type == "depth":
                values["type"] = "depth_camera"  # as gz-sim does: a depth image only
            if self.text("camera/depth_camera/clip/far"):  # gz-sensors: a depth image's own clip, when given
                values.update(depth_near=self.number("camera/depth_camera/clip/near", 0.0),
                              depth_far=self.number("camera/depth_camera/clip/far", 0.0))
        name = ""
        if self.plugin is not None:
            name = (self.plugin.findtext("camera_name") or self.plugin.findtext("cameraName") or "").strip()
        name = clean_topic(name) or (self.text("topic") if self.text("topic") not in _UNSET else "")
        name = clean_topic(name)
        values["topic"] = (name.removesuffix("image_raw").rstrip("/") if name != "image_raw" else "") \
            or clean_topic(self.name)
        if not self.text("update_rate") and self.plugin is not None:
            for tag in ("updateRate", "update_rate"):
                if (self.plugin.findtext(tag) or "").strip():
                    values["rate_hz"] = self.plugin_number(tag, 0.0)
                    break
        return values

    def plugin_number(self, tag: str, default: float) -> float:
        """A finite number in the plugin at ``tag``, or ``default`` when absent or empty."""
        text = (self.plugin.findtext(tag) or "").strip() if self.plugin is not None else ""
        if not text:
            return default
        value = _plugin_number(self.plugin, tag)
        if value is None:
            raise DescriptionError(f"sensor '{self.name}' has <{tag}> '{text[:40]}', which is not a "
                                   "finite number", location=self.location(f"plugin/{tag}"),
                                   hint="Write a plain number.")
        return value

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
            for tag in ("frame_name", "frameName", "frameId"):
                text = (self.plugin.findtext(tag) or "").strip()
                if text:
                    return text
        for tag in ("camera/optical_frame_id", "gz_frame_id", "ignition_frame_id", "frame_id"):
            if self.text(tag):
                return self.text(tag)
        return ""


def clean_topic(text: str) -> str:
    """A topic relative to the robot's namespace: no '~/', no leading or trailing '/'."""
    text = text.strip().removeprefix("~")
    return "/".join(part for part in text.split("/") if part)


def _range_output(plugin: ET.Element) -> bool:
    """gazebo_ros's ray sensor told to publish sensor_msgs/Range."""
    return (plugin.findtext("output_type") or "").strip().split("/")[-1] == "Range"


def _range_plugin(plugin: ET.Element) -> bool:
    """A plugin that reads a ray sensor as one range: gazebo_ros's (ROS 2 output_type Range,
    ROS 1 gazebo_ros_range) or hector's sonar."""
    filename = plugin.get("filename", "").lower()
    return _range_output(plugin) or "gazebo_ros_range" in filename or "sonar" in filename


def _gazebo_ros_plugin(plugin: ET.Element) -> bool:
    """Gazebo classic's ROS camera plugin family (gazebo_ros_camera, gazebo_ros_openni_kinect, ...),
    which publishes a depth sensor's image as well as its depth, cut off by its own parameters."""
    name = plugin.get("filename", "").lower()
    return "gazebo_ros" in name or "kinect" in name or "realsense" in name


def _plugin_number(plugin: ET.Element, tag: str) -> float | None:
    try:
        value = float((plugin.findtext(tag) or "").strip())
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def finite(text: str, owner: str, tag: str, location: Location) -> float:
    """``text`` as a finite number; a DescriptionError naming ``owner`` and ``<tag>`` otherwise."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise DescriptionError(f"{owner} has <{tag}> '{text[:40]}', which is not a finite number",
                               location=location, hint="Write a plain number.")
    return value
