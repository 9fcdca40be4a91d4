"""`mobot check PATH`: validate a scenario or robot description without running it."""

from __future__ import annotations

from pathlib import Path

import typer

from mobot_cli.cli import output
from mobot_cli.cli.args import parse_mappings
from mobot_cli.errors import ExitCode, UsageError

SCENARIO_SUFFIXES = (".yaml", ".yml")
ROBOT_SUFFIXES = (".urdf", ".xacro")


def check(
    path: Path = typer.Argument(..., help="A scenario (.yaml) or robot description (.urdf, .xacro)."),
    mappings: list[str] = typer.Argument(None, metavar="[NAME:=VALUE]...", help="xacro arguments for a robot."),
    json_: bool = typer.Option(False, "--json", help="Print the result as JSON."),
) -> int:
    """Validate a scenario or a robot description; exit 0 when it is usable, 2 when not."""
    if path.suffix in SCENARIO_SUFFIXES:
        result = _check_scenario(path)
    elif path.suffix in ROBOT_SUFFIXES:
        result = _check_robot(path, parse_mappings(mappings or []))
    else:
        raise UsageError(f"cannot tell what '{path}' is from its suffix",
                         hint="mobot check takes a scenario (.yaml) or a robot (.urdf, .urdf.xacro, .xacro).")
    if json_:
        output.emit_json(result)
    else:
        output.notices(result["notices"])
        output.check_result(result)
    return ExitCode.OK


def _check_scenario(path: Path) -> dict:
    from mobot_cli.run.prepare import prepare

    plan = prepare(path).plan
    return {"ok": True, "kind": "scenario", "path": str(path), "name": plan.name,
            "robots": [robot.name for robot in plan.robots], "steps": plan.total_steps,
            "duration": plan.total_steps / plan.physics.rate_hz, "notices": list(plan.notices)}


def _check_robot(path: Path, args: dict[str, str]) -> dict:
    from mobot_cli.assets.description import inspect_summary, load_robot

    desc = load_robot(str(path), args, Path.cwd())
    return {"ok": True, "kind": "robot", "path": str(path), **inspect_summary(desc),
            "notices": [str(n) for n in desc.notices]}
