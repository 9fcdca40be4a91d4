"""Which xacro argument switches a sensor on, for the error about a sensor a description lacks.

Descriptions often add a lidar or an IMU only when asked (the bundled mobot's
``<xacro:if value="$(arg lidar)">``), so ``sensors: {scan: ...}`` without ``args: {lidar: "true"}``
names a sensor that is not there. On that error path only, each boolean argument that is off
is turned on and the description expanded again (cached like any load), once per argument.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any, Callable

from mobot_cli.assets.description.robot import RobotDescription
from mobot_cli.assets.description.sensors import DescribedSensor
from mobot_cli.errors import MobotError

_ARG = re.compile(r"<xacro:arg\s[^>]*>")
_ATTR = re.compile(r"""(\w+)\s*=\s*(?:"([^"]*)"|'([^']*)')""")
OFF = ("false", "False", "0")


def arg_text(value: Any) -> str:
    """A xacro argument value as the text xacro sees ('true', not 'True')."""
    if isinstance(value, bool):
        return "true" if value else "false"
    return str(value)


def declared_args(files: tuple[Path, ...]) -> dict[str, str]:
    """Every ``<xacro:arg>`` the description's files declare: name -> default ("" for none)."""
    out: dict[str, str] = {}
    for path in files:
        try:
            text = Path(path).read_text(encoding="utf-8", errors="replace")
        except OSError:
            continue
        for tag in _ARG.findall(text):
            attrs = {m.group(1): m.group(2) if m.group(2) is not None else m.group(3)
                     for m in _ATTR.finditer(tag)}
            if "name" in attrs:
                out.setdefault(attrs["name"], attrs.get("default", ""))
    return out


def switch_on(desc: RobotDescription, args: dict[str, str], has: Callable[[tuple[DescribedSensor, ...]], bool],
              load: Callable[[dict[str, str]], RobotDescription]) -> str | None:
    """The boolean argument that, set to true, gives ``desc`` (loaded with ``args``) a sensor
    ``has`` accepts; None when none does. ``load`` loads the description with other args."""
    for name, default in declared_args(desc.files).items():
        if args.get(name, default) not in OFF:
            continue
        try:
            other = load({**args, name: "true"})
        except MobotError:  # that combination does not expand: not the switch
            continue
        if has(other.sensors):
            return name
    return None


def switch_text(desc: RobotDescription, args: dict[str, str],
                has: Callable[[tuple[DescribedSensor, ...]], bool],
                load: Callable[[dict[str, str]], RobotDescription]) -> tuple[str, str, str] | None:
    """When an argument switches on a sensor ``has`` accepts: what the message adds, the args
    that do it ({lidar: "true"}) and "" ; when none does: "", "" and a sentence listing the
    description's arguments; None for a description without arguments."""
    declared = declared_args(desc.files)
    if not declared:
        return None
    name = switch_on(desc, args, has, load)
    if name is None:
        listed = ", ".join(f"{n} (default {d})" if d else n for n, d in declared.items())
        return "", "", f"None of its xacro args adds one when set to true: {listed}."
    given = {**args, name: "true"}
    flow = "{" + ", ".join(f'{k}: "{v}"' for k, v in given.items()) + "}"
    return f"; it has one with {name}:=true (args: {flow})", flow, ""
