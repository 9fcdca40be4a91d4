"""`mobot check PATH`: validate a scenario or robot description without running it."""

from __future__ import annotations

import re
from pathlib import Path

import typer

from mobot_cli.cli import output
from mobot_cli.cli.args import parse_mappings
from mobot_cli.errors import ExitCode, UsageError

SCENARIO_SUFFIXES = (".yaml", ".yml")
ROBOT_SUFFIXES = (".urdf", ".xacro")
WORLD_SUFFIXES = (".world", ".sdf")  # an .sdf holding a <model> is a robot
SKIP_HELP = ("Leave out world models and robot visuals/collisions whose files are missing (Fuel includes, "
             "meshes), with a warning.")


def check(
    ctx: typer.Context,
    path: Path = typer.Argument(..., help="A scenario (.yaml), robot (.urdf, .xacro, .sdf model or model folder), "
                                         "world (.world, .sdf, .world.xacro, .sdf.xacro, bundled name), "
                                         "or run folder."),
    mappings: list[str] = typer.Argument(None, metavar="[NAME:=VALUE]...", help="xacro arguments for a robot."),
    json_: bool = typer.Option(False, "--json", help="Print the result as JSON."),
    skip_missing: bool = typer.Option(False, "--skip-missing", help=SKIP_HELP),
    repair: bool = typer.Option(False, "--repair", help="For a run folder: make a killed run's bag readable "
                                                        "(its complete chunks, with an index and metadata.yaml)."),
    set_: list[str] = typer.Option([], "--set", help="Override a scenario key, e.g. robots.mobot.pose.x=2.0 "
                                                     "(repeatable)."),
) -> int:
    """Validate a scenario, robot description or world; exit 0 when it is usable, 2 when not.

    Given a run folder, say how the run ended: exit 0 ok, 1 expectations failed, 2 incomplete
    (killed, interrupted or files missing), 3 simulation fault.
    """
    env = ctx.obj
    model_folder = (path / "model.config").is_file()  # a Gazebo model: a robot description
    if path.is_dir() and not model_folder:
        return _check_run_folder(env, path, json_, repair)
    if repair:
        raise UsageError("--repair is for run folders", hint="Give the folder that mobot run --out wrote.")
    if set_ and path.suffix not in SCENARIO_SUFFIXES:
        raise UsageError("--set overrides keys of a scenario; it does not apply to a robot or world",
                         hint="Give xacro arguments to a robot as NAME:=VALUE.")
    sdf_xacro = path.name.endswith(".sdf.xacro")
    if path.suffix in SCENARIO_SUFFIXES:
        result = _check_scenario(path, skip_missing, set_)
    elif path.name.endswith(".world.xacro") or (sdf_xacro and _is_world(path)):
        result = _check_world(path, skip_missing)
    elif path.suffix in ROBOT_SUFFIXES or model_folder or (path.suffix == ".sdf" and not _is_world(path)):
        result = _check_robot(path, parse_mappings(mappings or []), skip_missing)
    elif path.suffix in WORLD_SUFFIXES or _bundled_world(path):
        result = _check_world(path, skip_missing)
    else:
        raise UsageError(f"cannot tell what '{path}' is from its suffix",
                         hint="mobot check takes a scenario (.yaml), a robot (.urdf, .urdf.xacro, .xacro, "
                              ".sdf) or a world (.world, .sdf, or a bundled world's name).")
    if json_:
        output.emit_json(env, result)
    else:
        output.notices(env, result["notices"])
        output.check_result(env, result)
    return ExitCode.OK


def _check_scenario(path: Path, skip_missing: bool, overrides: list[str]) -> dict:
    from mobot_cli.scenario.prepare import prepare
    from mobot_cli.sim.preflight import check_spawns

    plan = prepare(path, [*overrides, *(["skip_missing=true"] if skip_missing else [])]).plan
    check_spawns(plan)  # robots inside furniture or below the floor are bad input too
    return {"ok": True, "kind": "scenario", "path": str(path), "name": plan.name,
            "robots": [robot.name for robot in plan.robots], "steps": plan.total_steps,
            "duration": plan.total_steps / plan.physics.rate_hz, "notices": list(plan.notices)}


def _check_robot(path: Path, args: dict[str, str], skip_missing: bool) -> dict:
    from mobot_cli.assets.description.describe import load_robot
    from mobot_cli.assets.description.robot import inspect_summary
    from mobot_cli.sim.preflight import check_robot

    desc = load_robot(str(path), args, Path.cwd(), skip_missing)
    check_robot(desc.name or "robot", desc.urdf, desc.root_link, str(desc.source))  # PyBullet loads what a run loads
    return {"ok": True, "kind": "robot", "path": str(path), **inspect_summary(desc),
            "notices": [str(n) for n in desc.notices]}


def _is_world(path: Path) -> bool:
    """True when an .sdf file holds a <world> (a cheap look; the loader parses it properly)."""
    try:
        head = path.read_text(encoding="utf-8", errors="replace")
    except OSError:
        return True  # let the world loader report the unreadable file
    return re.search(r"<world[\s>]", head) is not None


def _bundled_world(path: Path) -> bool:
    from mobot_cli.assets.world.worldplan import bundled_world_names

    return not path.exists() and str(path) in bundled_world_names()


def _check_world(path: Path, skip_missing: bool) -> dict:
    from mobot_cli.assets.world.worldplan import load_world
    from mobot_cli.sim.preflight import check_world

    loaded = load_world(str(path), Path.cwd(), skip_missing=skip_missing)
    check_world(loaded.plan)  # every mesh loads into PyBullet
    return {"ok": True, **loaded.summary, "notices": list(loaded.notices)}


def _check_run_folder(env, path: Path, json_: bool, repair: bool) -> int:
    from mobot_cli.record.folder import repair_run, run_status

    repaired = repair_run(path) if repair else None
    result = run_status(path)
    if repaired is not None:
        result["repaired"] = repaired
    if json_:
        output.emit_json(env, result)
    else:
        output.run_folder_status(env, result)
    return result["exit_code"]
