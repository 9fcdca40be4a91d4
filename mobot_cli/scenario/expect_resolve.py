"""``expect:`` items to plan Expectations: robot names checked, fleets expanded, times to log rows."""

from __future__ import annotations

from typing import Sequence

from mobot_cli.errors import ScenarioError, did_you_mean, shown
from mobot_cli.plan import Event, Expectation, GoalStep, RobotPlan
from mobot_cli.scenario.expect_model import DEFAULT_VISIT_RADIUS, OVER_TIME, ExpectSpec, OdomErrorSpec, UprightSpec
from mobot_cli.scenario.goals import area_form, area_polygon
from mobot_cli.scenario.model import Scenario
from mobot_cli.scenario.source import Source
from mobot_cli.scenario.units import steps

ALL = "all"


def resolve_expectations(scenario: Scenario, source: Source, robots: Sequence[RobotPlan],
                         events: Sequence[Event], log_every: int,
                         total: int) -> tuple[tuple[Expectation, ...], list[str]]:
    """Expectations in file order (a fleet's name gives one per member) and notices."""
    rate = scenario.physics.rate_hz
    plans = [*robots, *(e.spawn for e in events if e.spawn is not None)]
    names = [r.name for r in plans]
    fleets = {spec.name: [spec.name.replace("{i}", str(i)) for i in range(spec.count)]
              for spec in scenario.robots if spec.count is not None}
    out: list[Expectation] = []
    notices: list[str] = []
    for index, spec in enumerate(scenario.expect):
        path = ("expect", index)
        step = None
        if spec.at != "end":
            step, note = _log_row(spec.at, rate, log_every, total)
            if note:
                notices.append(f"{source.locate_key(path + ('at',))}: {note}")
        if spec.robot == ALL or spec.robot in names:
            members = [spec.robot]
        elif spec.robot in fleets:
            members = fleets[spec.robot]
        else:
            raise ScenarioError(f"expectation names robot {shown(spec.robot)}, which is not in the scenario",
                                location=source.locate_key(path + ("robot",)),
                                hint=did_you_mean(spec.robot, [*names, *fleets, ALL]))
        if spec.kind == "goal":
            _goal_command(spec.goal.command, {r.name: r for r in plans}[members[0]],
                          source.locate_key(path + ("goal", "command")))
        if spec.kind == "metric" and spec.metric.command is not None:
            _goal_command(spec.metric.command, {r.name: r for r in plans}[members[0]],
                          source.locate_key(path + ("metric", "command")))
        limits = _limits(spec)
        points = area_polygon(spec.coverage.area) if spec.kind == "coverage" else \
            tuple((float(x), float(y)) for x, y in spec.visits) if spec.kind == "visits" else ()
        status = spec.goal.status if spec.kind == "goal" else ""
        metric = spec.metric.name if spec.kind == "metric" else ""
        out.extend(Expectation(robot=name, kind=spec.kind, limits=limits, step=step, points=points, status=status,
                               metric=metric) for name in members)
    return tuple(out), notices


def _log_row(at: float, rate: int, log_every: int, total: int) -> tuple[int, str | None]:
    """The step of the log row nearest ``at`` (so a check uses a row of odom/<robot>.csv)."""
    exact = steps(at, rate)
    if exact >= total:
        return exact, None  # the end of the run, or after it: the check says the run ended first
    row = min(total, (exact + log_every // 2) // log_every * log_every)
    if row == exact:
        return row, None
    return row, f"expectation at {at:g} s is checked on the nearest log row, {row / rate:g} s"


def _goal_command(index: int, robot: RobotPlan, where) -> None:
    """A located error unless the robot's command at that index is a goal."""
    goals = {c.index: c.kind for c in robot.commands if isinstance(c, GoalStep)}
    if index not in goals:
        listed = ", ".join(f"{i} ({kind})" for i, kind in goals.items()) or "none"
        raise ScenarioError(f"robot '{robot.name}' has no goal command at index {index} of its commands "
                            f"(its goal commands: {listed})", location=where,
                            hint="Count the robot's commands from 0; goto, path, patrol and coverage are goals.")


def _limits(spec: ExpectSpec) -> tuple[tuple[str, float], ...]:
    """The check's numbers, defaults filled, in a fixed order."""
    kind = spec.kind
    deadline = (("within", spec.deadline),) if spec.deadline is not None else ()
    if kind == "reaches":
        return (("x", float(spec.reaches.x)), ("y", float(spec.reaches.y)), ("radius", float(spec.reaches.radius)),
                *deadline)
    if kind == "visits":
        return (("radius", float(spec.radius or DEFAULT_VISIT_RADIUS)), *deadline)
    if kind == "coverage":
        return (("min", float(spec.coverage.min)), *deadline)
    if kind == "goal":
        return (("command", float(spec.goal.command)),)
    if kind == "metric":
        return tuple((k, float(v)) for k, v in spec.metric.model_dump(exclude_none=True).items() if k != "name")
    if kind == "within":
        shape = spec.within.model_dump(exclude_none=True)
        order = ("x", "y", "radius") if "radius" in shape else ("xmin", "xmax", "ymin", "ymax")
        return tuple((k, float(shape[k])) for k in order)
    if kind == "collisions":
        return (("max", float(spec.collisions)),)
    if kind == "distance":
        return tuple((k, float(v)) for k, v in spec.distance.model_dump(exclude_none=True).items())
    if kind == "clearance":
        return (("min", float(spec.clearance.min)),)
    if kind == "upright":
        upright = spec.upright if isinstance(spec.upright, UprightSpec) else UprightSpec()
        return (("max_tilt", float(upright.max_tilt)),)
    odom = spec.odom_error if isinstance(spec.odom_error, OdomErrorSpec) \
        else OdomErrorSpec(position=spec.odom_error)
    return tuple((k, float(v)) for k, v in odom.model_dump(exclude_none=True).items())


def expect_document(expectations: Sequence[Expectation], rate: int) -> dict[str, list]:
    """``expect:`` as the resolved scenario writes it: one item per robot, defaults filled."""
    if not expectations:
        return {}
    items = []
    for e in expectations:
        limits = dict(e.limits)
        if e.kind in OVER_TIME or e.kind == "goal":
            items.append(_over_time(e, limits))
            continue
        if e.kind == "metric":
            check = {"name": e.metric, **{k: int(v) if k == "command" else v for k, v in limits.items()}}
            items.append({"robot": e.robot, "metric": check})
            continue
        if e.kind == "collisions":
            check = int(limits["max"])
        else:
            check = limits
        items.append({"robot": e.robot, e.kind: check, "at": "end" if e.step is None else e.step / rate})
    return {"expect": items}


def _over_time(e: Expectation, limits: dict[str, float]) -> dict:
    """A check over time (or a goal check) as the scenario writes it."""
    item: dict = {"robot": e.robot}
    if e.kind == "reaches":
        item["reaches"] = {k: limits[k] for k in ("x", "y", "radius")}
    elif e.kind == "visits":
        item.update(visits=[list(p) for p in e.points], radius=limits["radius"])
    elif e.kind == "coverage":
        item["coverage"] = {"area": area_form(e.points), "min": limits["min"]}
    else:
        item["goal"] = {"command": int(limits["command"]), "status": e.status}
    if "within" in limits:
        item["within"] = limits["within"]
    return item
