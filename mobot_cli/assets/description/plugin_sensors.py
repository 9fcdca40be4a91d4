"""Model plugins that are sensors in practice: IMUs read as mobot's imu sensor, others named.

Some robots carry a sensor as a model plugin rather than a <sensor> element: hector's
``libhector_gazebo_ros_imu.so`` and ROS 1 gazebo_plugins' ``libgazebo_ros_imu.so`` compute an
IMU reading of a link (``<bodyName>``) themselves. Each is read as the imu sensor it is, named
after the plugin, with the plugin's topic, frame, rate and gaussian noise (hector's
``rateGaussianNoise``/``accelGaussianNoise``, one number or x y z per axis (their root mean
square, with a notice when they differ: mobot's IMU has one stddev), replaced by ``gaussianNoise`` when that is given
and not 0; gazebo_ros_imu's ``gaussianNoise`` on both). Their drift, bias, scale error and
offsets are not modelled. A plugin on the link of an imu <sensor>, or on its topic, is that
same IMU (turtlebot3's descriptions carry both): the <sensor> is read, the plugin not again.
GPS, magnetometer, altimeter and similar plugins mobot does not simulate are named with the
left-out sensors. gz-sim's systems (``gz-sim-imu-system``, ``ignition::gazebo::systems::Imu``)
are not sensors: they serve the model's <sensor> elements, which are read as such.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

from mobot_cli.assets.description.sensor_xml import clean_topic, finite
from mobot_cli.errors import Location, Notice

# words in a plugin's file name -> what it senses (plugins mobot does not simulate)
OTHER_PLUGINS = (("gps", "GPS"), ("navsat", "GPS"), ("magnetic", "magnetometer"),
                 ("magnetometer", "magnetometer"), ("barometer", "altimeter"), ("altimeter", "altimeter"))


def plugin_sensors(robot: ET.Element, source: Path, skipped: list[str],
                   notices: list[Notice] | None = None) -> list[dict]:
    """DescribedSensor values of every IMU model plugin of an expanded URDF, in document order;
    other sensor plugins are added to ``skipped``; per-axis noise is said in ``notices``."""
    out = []
    for gazebo in robot.findall("gazebo"):
        for plugin in gazebo.findall("plugin"):
            filename = plugin.get("filename", "").strip()
            stem = Path(filename).name.lower()
            name = plugin.get("name", "").strip() or Path(filename).stem.removeprefix("lib")
            if _gz_system(filename, name):  # gz-sim's Imu, NavSat ... systems serve <sensor> elements
                continue
            if "imu" in stem and "imu_sensor" not in stem:  # imu_sensor is a <sensor> plugin
                imu = _imu(plugin, stem, name, robot, source, notices if notices is not None else [])
                if imu is None:
                    skipped.append(f"IMU plugin '{name}' (no <bodyName>)")
                else:
                    out.append(imu)
                continue
            what = next((label for word, label in OTHER_PLUGINS if word in stem), None)
            if what is not None and "ros" in stem:
                skipped.append(f"{what} plugin '{name}' ({Path(filename).name})")
    return out


def _gz_system(filename: str, name: str) -> bool:
    """Whether a plugin is a gz-sim (ignition-gazebo) system: ``gz-sim-imu-system``,
    ``libignition-gazebo-imu-system.so``, ``gz::sim::systems::Imu``. Such a system makes the
    model's <sensor> elements of its kind work; it is no sensor of its own."""
    stem = Path(filename).name.lower().removesuffix(".so")
    return stem.endswith("-system") or "::systems::" in name


def _imu(plugin: ET.Element, stem: str, name: str, robot: ET.Element, source: Path,
         notices: list[Notice]) -> dict | None:
    """One IMU plugin's values; None when it names no link and Gazebo would not load it."""
    hector = "hector" in stem
    link = _text(plugin, "bodyName")
    if not link:
        if not hector:
            return None  # gazebo_ros_imu refuses to load without <bodyName>
        link = _root_link(robot)  # hector takes the model's canonical link: the URDF's root
    number = _reader(plugin, name, source)
    if hector:  # hector's noises are vectors (x y z), as MiR writes them; a single number is all three
        rate, accel = _axes(plugin, name, "rateGaussianNoise", source, notices), \
            _axes(plugin, name, "accelGaussianNoise", source, notices)
        both = number("gaussianNoise", 0.0)
        if both != 0.0:
            rate = accel = both
        topic, frame = _text(plugin, "topicName") or "imu", _text(plugin, "frameId")
    else:
        rate = accel = number("gaussianNoise", 0.0)
        topic, frame = _text(plugin, "topicName") or "default_imu", _text(plugin, "frameName")
    hz = number("updateRate", 0.0)
    return dict(name=name, type="imu", link=link, rate_hz=hz, noise_stddev=abs(rate),
                accel_noise_stddev=abs(accel), topic=clean_topic(topic), frame_id=frame)


def _axes(plugin: ET.Element, name: str, tag: str, source: Path, notices: list[Notice]) -> float:
    """A hector noise stddev written as one number or as x y z: one stddev for all axes (mobot's
    IMU has one), the root mean square of the three, with a notice when they differ."""
    text = _text(plugin, tag)
    where = Location(file=source, key=f"gazebo.plugin.{name}.{tag}")
    words = text.split()
    if len(words) != 3:
        return finite(text, f"plugin '{name}'", tag, where) if text else 0.0
    values = [finite(word, f"plugin '{name}'", tag, where) for word in words]
    rms = math.sqrt(sum(v * v for v in values) / 3)
    if max(values) - min(values) > 1e-3 * max(abs(v) for v in values):
        notices.append(Notice(f"plugin '{name}' gives <{tag}> per axis ({' '.join(f'{v:g}' for v in values)}): "
                              f"mobot's IMU has one stddev for all axes, their root mean square {rms:.4g}", where))
    return rms


def _root_link(robot: ET.Element) -> str:
    children = {(joint.find("child").get("link", "") if joint.find("child") is not None else "")
                for joint in robot.findall("joint")}
    return next((link.get("name", "") for link in robot.findall("link") if link.get("name", "") not in children), "")


def _text(plugin: ET.Element, tag: str) -> str:
    return (plugin.findtext(tag) or "").strip()


def _reader(plugin: ET.Element, name: str, source: Path):
    def number(tag: str, default: float) -> float:
        text = _text(plugin, tag)
        if not text:
            return default
        return finite(text, f"plugin '{name}'", tag, Location(file=source, key=f"gazebo.plugin.{name}.{tag}"))
    return number
