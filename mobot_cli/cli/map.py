"""`mobot map WORLD`: the world's occupancy grid as nav2 map_server files (map.yaml + map.pgm)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Optional

import typer

from mobot_cli.cli import output
from mobot_cli.errors import UsageError, cannot_write

MAX_RESOLUTION = 10.0  # m per cell
MIN_RESOLUTION = 0.001


def map_(
    ctx: typer.Context,
    world: str = typer.Argument(..., help="A bundled world name, a Gazebo .world/.sdf (or .world.xacro) file, or a "
                                          "scenario (.yaml) whose world it maps (a generated one too)."),
    resolution: float = typer.Option(0.05, "--resolution", help="Cell side, m."),
    band: str = typer.Option("0.02,2.0", "--band", metavar="ZMIN,ZMAX",
                             help="Heights above the floor (m) whose geometry is an obstacle."),
    size: Optional[str] = typer.Option(None, "--size", metavar="W,H", help="Map size, m (default: the world's)."),
    origin: Optional[str] = typer.Option(None, "--origin", metavar="X,Y",
                                         help="World x, y of the map's lower-left corner, m."),
    robot_radius: float = typer.Option(0.0, "--robot-radius", help="Inflate obstacles by this radius, m."),
    floor: Optional[float] = typer.Option(None, "--floor", metavar="Z",
                                          help="Height of the floor the band is measured from, m (default: the "
                                               "floor under a scenario's robots, else under the origin)."),
    out: Path = typer.Option(Path("."), "--out", help="Folder for map.yaml and map.pgm."),
    skip_missing: bool = typer.Option(False, "--skip-missing", help="Leave out world models whose files are "
                                      "missing (Fuel includes, meshes), with a warning, instead of stopping."),
) -> None:
    """Write the world's occupancy grid for nav2's map_server: map.yaml and a trinary map.pgm."""
    from mobot_cli.assets.world import occupancy
    from mobot_cli.ros.map_files import grid_cells, write_map

    _check("--resolution", resolution, MIN_RESOLUTION, MAX_RESOLUTION)
    _check("--robot-radius", robot_radius, 0.0, 10.0, strict=False)
    low, high = _pair("--band", band, "ZMIN,ZMAX")
    if not low < high:
        raise UsageError(f"--band {band}: ZMIN must be below ZMAX", hint="e.g. --band 0.02,2.0")
    extent = _pair("--size", size, "W,H") if size else None
    if extent and min(extent) <= 0:
        raise UsageError(f"--size {size}: width and height must be positive", hint="e.g. --size 12,10")
    corner = _pair("--origin", origin, "X,Y") if origin else None
    if floor is not None:
        _check("--floor", floor, -1e4, 1e4)
    loaded, starts = _world(world, skip_missing)
    if floor is None:
        floor = _floor(loaded.plan, starts)
    try:
        grid = occupancy.grid_for(loaded.plan, resolution, (floor + low, floor + high), corner, extent)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    occ = occupancy.occupancy(loaded.plan, grid, floor, (low, high))
    occupied = occ.inflated(robot_radius)
    try:
        files = write_map(out, grid_cells(occupied), resolution, (grid.x0, grid.y0, 0.0))
    except OSError as exc:
        raise cannot_write(out, exc) from None
    output.notices(ctx.obj, [str(n) for n in loaded.notices])
    ctx.obj.stdout.write(f"{files.yaml}: {grid.nx} x {grid.ny} cells of {resolution:g} m from "
                         f"({grid.x0:g}, {grid.y0:g}), {int(occupied.sum())} occupied "
                         f"(band {low:g}..{high:g} m above the floor at z = {floor:g} m"
                         + (f", inflated by {robot_radius:g} m" if robot_radius else "") + ")\n")


def _world(world: str, skip_missing: bool):
    """The world to map: a world (name or file) loaded, or a scenario's world (its ``world:``,
    generated ones included) with the notices loading it gave; and where the scenario's robots
    are spawned (x, y, z as asked), none for a world."""
    from mobot_cli.assets.world.loaded import LoadedWorld
    from mobot_cli.assets.world.worldplan import load_world
    from mobot_cli.scenario.prepare import SCENARIO_SUFFIXES, prepare

    if world.endswith(SCENARIO_SUFFIXES):
        plan = prepare(world, ["skip_missing=true"] if skip_missing else []).plan
        return LoadedWorld(plan=plan.world, notices=plan.notices), [tuple(r.pose.xyz) for r in plan.robots]
    return load_world(world, Path.cwd(), skip_missing=skip_missing), []


def _floor(world, starts: list) -> float:
    """The floor the band is measured from: the one a scenario's robots stand on (the lowest), or
    the world's under the origin."""
    from mobot_cli.assets.world import occupancy
    from mobot_cli.assets.world.freespace import robot_floor

    if starts:
        return min(robot_floor(world, start) for start in starts)
    return occupancy.floor_under(world, [])


def _pair(option: str, text: str, form: str) -> tuple[float, float]:
    parts = text.split(",")
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        values = ()
    if len(values) != 2 or not all(math.isfinite(v) and abs(v) <= 1e5 for v in values):
        raise UsageError(f"{option} '{text}' is not {form} (two finite numbers, a comma between)",
                         hint=f"e.g. {option} " + {"ZMIN,ZMAX": "0.02,2.0", "W,H": "12,10"}.get(form, "-6,-5"))
    return values


def _check(option: str, value: float, low: float, high: float, strict: bool = True) -> None:
    ok = math.isfinite(value) and (low < value if strict else low <= value) and value <= high
    if not ok:
        raise UsageError(f"{option} {value:g} is out of range: give {'more than' if strict else 'at least'} "
                         f"{low:g} and at most {high:g}")
