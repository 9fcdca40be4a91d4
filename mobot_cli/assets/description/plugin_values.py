"""Values of a Gazebo <plugin> block, and the one warning when its wheel layout disagrees with
the wheels' geometry: shared by every drive's detection (drive.py, holonomic.py)."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

from mobot_cli.assets.description.wheels import Wheel
from mobot_cli.errors import Location, Notice

# Plugin values farther than this from the wheel geometry get a warning.
DISAGREEMENT = 0.02


def texts(plugin: ET.Element, *tags: str) -> list[str]:
    """Values of the children named ``tags``, as <t>v</t> or <t value="v"/>, in tag order."""
    values = []
    for tag in tags:
        for child in plugin.findall(tag):
            value = (child.text or "").strip() or child.get("value", "").strip()
            if value:
                values.append(value)
    return values


def number(plugin: ET.Element, *tags: str) -> float | None:
    for text in texts(plugin, *tags):
        try:
            return float(text)
        except ValueError:
            continue
    return None


def disagreement(who: str, wheels: list[tuple[str, Wheel]], radius: float | None,
                 separation: float | None, notices: list[Notice], file: Path | None, *,
                 says: str = "says", whose: str = "the plugin's", holonomic: bool = False) -> None:
    """One warning when a plugin's (``who``: "the X plugin") or a controller's radius or
    separation is > 2 % off the wheel geometry. A ``holonomic`` base's body follows its
    commanded twist in mobot (sim/bullet/holonomic.py), and so does a skid-steer base's (more
    than one wheel a side: its twist loop, sim/bullet/twist_trim.py), so for those the warning
    says what Gazebo would do and what mobot does instead."""
    parts, effects = [], []
    left = [w.y for side, w in wheels if side == "left"]
    right = [w.y for side, w in wheels if side == "right"]
    if separation and left and right:
        apart = abs(sum(left) / len(left) - sum(right) / len(right))
        if apart > 0 and abs(separation - apart) > DISAGREEMENT * apart:
            parts.append(f"wheel_separation {separation:.3f} m, but its wheel joints are "
                         f"{apart:.3f} m apart")
            effects.append(f"turns {_percent(separation / apart)} than commanded")
    radii = [w.radius for _, w in wheels if w.radius]
    if radius and radii:
        measured = sum(radii) / len(radii)
        if abs(radius - measured) > DISAGREEMENT * measured:
            parts.append(f"wheel_radius {radius:.3f} m, but its wheels' collisions have radius "
                         f"{measured:.3f} m")
            effects.append(f"drives {_percent(measured / radius)} than commanded")
    sides = [side for side, _ in wheels]
    skid = max(sides.count("left"), sides.count("right")) > 1
    if parts and skid and not holonomic:
        notices.append(Notice(
            f"{who} {says} {'; and '.join(parts)}: mobot uses {whose} values, as Gazebo does, where the "
            f"robot {' and '.join(effects)}; mobot's skid-steer twist loop drives the body as commanded "
            "(drive: {twist_feedback: false} to leave it out; wheel_radius / wheel_separation to use the "
            "geometry)", Location(file=file)))
    elif parts and holonomic:
        notices.append(Notice(
            f"{who} {says} {'; and '.join(parts)}: in Gazebo the robot {' and '.join(effects)}; mobot "
            f"moves a holonomic base as commanded and turns its wheels and integrates odometry with {whose} "
            "values, so neither shows it (set drive: wheel_radius / wheel_separation to use the geometry)",
            Location(file=file)))
    elif parts:
        notices.append(Notice(
            f"{who} {says} {'; and '.join(parts)}: mobot uses {whose} values, "
            f"as Gazebo does, so the robot {' and '.join(effects)} (set drive: wheel_radius / "
            "wheel_separation to use the geometry)", Location(file=file)))


def _percent(ratio: float) -> str:
    """'11 % more' or '9 % less' for a ratio of achieved to commanded motion."""
    return f"{abs(ratio - 1) * 100:.0f} % {'more' if ratio > 1 else 'less'}"
