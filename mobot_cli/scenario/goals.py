"""Goal commands to GoalSteps: defaults filled, points checked against the world, lanes planned.

The same function serves a scenario's ``commands:`` (errors located in the file) and a live
``goto`` request (no location). Coverage lanes are planned here, once, from the world's
static geometry, so the plan (and the resolved scenario) says exactly where the robot goes.
"""

from __future__ import annotations

from typing import Callable

from mobot_cli.common.polygon import DEFAULT_FOOTPRINT, box_polygon, footprint_radius
from mobot_cli.errors import Location, ScenarioError
from mobot_cli.plan import GoalControl, GoalStep, WorldPlan
from mobot_cli.scenario.goal_model import GoalFields
from mobot_cli.scenario.units import steps

DEFAULT = GoalControl()
PLAN_CELL = 0.05  # m: the grid coverage lanes are planned on (finer for spacings under 0.15 m)
PLAN_CELLS = 2000  # ... but never more cells than this along the area's longer side
PLAN_MARGIN = 1.0  # m around the area where the route between lane pieces may run
# A robot whose footprint is unknown (a description without collision geometry) is taken as this.
HINT = "Goals must lie in free space: trajectory.png of any run in this world shows its floor plan."

Locate = Callable[[tuple], "Location | None"]


def goal_step(cmd: GoalFields, step: int, index: int, rate: int, world: WorldPlan | None,
              footprint: tuple[float, float, float, float] | None, locate: Locate,
              notices: list[str], start: tuple[float, float, float] | None = None) -> GoalStep:
    """One goal command as a GoalStep starting at ``step``; ``locate`` turns a key path below
    the command into a Location (None for a live request). ``start``: where the robot is (x, y
    and its root link's z) or is spawned (z as asked, 0 when left to the floor): goal points are
    checked in the band above the floor it stands on (freespace.robot_floor)."""
    kind = cmd.goal
    control = _control(cmd, rate, footprint)
    floor = None
    if world is not None and start is not None and kind != "coverage":
        from mobot_cli.assets.world.freespace import robot_floor

        floor = robot_floor(world, start)
    if kind == "goto":
        point = (float(cmd.goto.x), float(cmd.goto.y))
        _free(world, point, kind, locate((kind,)), floor)
        return GoalStep(step=step, index=index, kind=kind, points=(point,), yaw=cmd.goto.yaw, control=control)
    if kind in ("path", "patrol"):
        points = tuple((float(x), float(y)) for x, y in getattr(cmd, kind))
        for i, point in enumerate(points):
            _free(world, point, f"{kind} point {i}", locate((kind, i)), floor)
        return GoalStep(step=step, index=index, kind=kind, points=points, laps=cmd.laps, control=control)
    polygon = area_polygon(cmd.coverage.area)
    try:
        points, skipped = plan_coverage(world, polygon, cmd.coverage.spacing, footprint or DEFAULT_FOOTPRINT)
    except ValueError as exc:
        raise ScenarioError(str(exc), location=locate(("coverage", "area")),
                            hint="Give an area larger than the robot, clear of furniture.") from None
    if skipped:
        where = locate(("coverage",))
        notices.append((f"{where}: " if where else "") + f"coverage: {skipped} lane piece"
                       f"{'s' if skipped > 1 else ''} cannot be reached from the first lane through "
                       f"free space and {'are' if skipped > 1 else 'is'} left out")
    return GoalStep(step=step, index=index, kind=kind, points=tuple(points), area=polygon,
                    spacing=float(cmd.coverage.spacing), control=control)


def _control(cmd: GoalFields, rate: int, footprint) -> GoalControl:
    tolerance = cmd.goto.tolerance if cmd.goto is not None else cmd.tolerance
    return GoalControl(
        max_linear=cmd.max_linear or DEFAULT.max_linear, max_angular=cmd.max_angular or DEFAULT.max_angular,
        linear_acceleration=cmd.acceleration or DEFAULT.linear_acceleration,
        angular_acceleration=cmd.angular_acceleration or DEFAULT.angular_acceleration,
        tolerance=tolerance or DEFAULT.tolerance, yaw_tolerance=DEFAULT.yaw_tolerance,
        localization=cmd.localization or DEFAULT.localization,
        timeout=None if cmd.timeout is None else max(1, steps(cmd.timeout, rate)),
        planner=cmd.planner,
        inflation=0.0 if cmd.planner is None else
        cmd.inflation if cmd.inflation is not None else footprint_radius(footprint or DEFAULT_FOOTPRINT),
        local=cmd.local or "",
        stuck_time=DEFAULT.stuck_time if cmd.stuck_time is None else float(cmd.stuck_time),
        danger_distance=DEFAULT.danger_distance if cmd.danger_distance is None else float(cmd.danger_distance))


def _free(world: WorldPlan | None, point: tuple[float, float], what: str, where: Location | None,
          floor: float | None = None) -> None:
    """A located error when ``point`` lies inside a static body of the world, in the band above
    ``floor`` (the robot's; None: the world's probed floor)."""
    if world is None:
        return
    from mobot_cli.assets.world.freespace import obstacle_at  # the floor plan: only for goals

    inside = obstacle_at(world, *point, floor=floor)
    if inside is not None:
        raise ScenarioError(f"{what} ({point[0]:g}, {point[1]:g}) is inside {inside}", location=where, hint=HINT)


def _is_box(area) -> bool:
    return len(area) == 4 and all(isinstance(v, (int, float)) for v in area)


def plan_coverage(world: WorldPlan | None, polygon, spacing: float,
                  footprint: tuple[float, float, float, float]) -> tuple[list[tuple[float, float]], int]:
    """Lawn-mower waypoints over ``polygon``'s free space and the lane pieces left out.

    The robot's centre keeps half its footprint's width inside the area (so its footprint
    reaches the area's edges) and its footprint's circumscribed radius away from obstacles
    (so it can turn in place anywhere on the route). ValueError when no lane fits.
    """
    from mobot_cli.assets.world.freespace import obstacle_mask
    from mobot_cli.common.boustrophedon import lawnmower
    from mobot_cli.common.raster import Grid, dilate, fill_polygon

    xmin, xmax, ymin, ymax = footprint
    half_width = max(abs(ymin), abs(ymax))
    radius = footprint_radius(footprint)
    xs, ys = [p[0] for p in polygon], [p[1] for p in polygon]
    cell = max(min(PLAN_CELL, spacing / 3.0), max(max(xs) - min(xs), max(ys) - min(ys)) / PLAN_CELLS)
    pad = radius + PLAN_MARGIN
    grid = Grid.covering(min(xs) - pad, max(xs) + pad, min(ys) - pad, max(ys) + pad, cell)
    obstacles = obstacle_mask(world, grid) if world is not None else grid.empty()
    passable = ~dilate(obstacles, radius / cell)
    inside = grid.empty()
    fill_polygon(inside, grid, polygon)
    lanes = inside & ~dilate(~inside, half_width / cell) & passable
    if not lanes.any():
        raise ValueError(f"the coverage area has no free space where the robot fits (its centre must stay "
                         f"{half_width:.2f} m inside the area and {radius:.2f} m from obstacles)")
    return lawnmower(lanes, passable, grid, spacing)


def area_polygon(area) -> tuple[tuple[float, float], ...]:
    """An area as the scenario gives it ([xmin, xmax, ymin, ymax] or [[x, y], ...]) as a polygon."""
    return tuple(box_polygon(*area)) if _is_box(area) else tuple((float(x), float(y)) for x, y in area)


def area_form(polygon) -> list:
    """An area polygon as a scenario writes it: [xmin, xmax, ymin, ymax] for a box, else its points."""
    xs, ys = sorted({p[0] for p in polygon}), sorted({p[1] for p in polygon})
    if len(xs) == 2 and len(ys) == 2 and list(polygon) == box_polygon(xs[0], xs[1], ys[0], ys[1]):
        return [xs[0], xs[1], ys[0], ys[1]]
    return [list(point) for point in polygon]
