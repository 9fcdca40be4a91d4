"""``mobot plot``: redraw trajectory.png from a run folder's CSV files, or overlay a sweep's runs."""

from __future__ import annotations

import csv
import json
from dataclasses import dataclass, field
from pathlib import Path

from mobot_cli.errors import MobotError, UsageError
from mobot_cli.record.folder import is_run_folder, is_sweep_folder
from mobot_cli.record.summary import RunRecord
from mobot_cli.record.trajectory import draw, drawn

MAX_ODOMETRY_TRACKS = 10  # more dashed lines than this (a sweep) hide the true paths


@dataclass
class PlotResult:
    """What ``mobot plot`` drew, and what it could not."""

    out: Path
    tracks: int
    runs: int
    notices: list[str] = field(default_factory=list)


@dataclass
class _Points:
    label: str
    true: list[tuple[float, float]] = field(default_factory=list)
    odom: list[tuple[float, float]] = field(default_factory=list)
    start_z: float | None = None  # the root link's height at the first row (the floor plan's band)
    yaw: list[float] = field(default_factory=list)  # true heading, for coverage sweeps
    swept: list = field(default_factory=list)  # run.sweep.Sweep


def replot(folder: Path, out: Path | None = None) -> PlotResult:
    """Draw the run (or every run of the sweep) in ``folder`` to ``out`` (default: folder/trajectory.png)."""
    if is_sweep_folder(folder):
        runs = sorted(p for p in (folder / "runs").iterdir() if is_run_folder(p))
        prefix = True
    elif is_run_folder(folder):
        runs, prefix = [folder], False
    else:
        raise UsageError(f"'{folder}' is neither a run folder nor a sweep folder",
                         hint="Give the folder that mobot run --out or mobot sweep --out wrote.")
    params = _swept_values(folder) if prefix else {}
    tracks = []
    for run in runs:
        for track in read_tracks(run):
            if prefix:  # "0001/mobot (yaw=0.5)"
                track.label = f"{run.name}/{track.label}" + (f" ({params[run.name]})" if params.get(run.name) else "")
            tracks.append(track)
    if not tracks:
        raise UsageError(f"'{folder}' holds no odometry CSV files to draw",
                         hint="Run with log.formats including csv, and let the run start.")
    result = PlotResult(out=out or folder / "trajectory.png", tracks=len(tracks), runs=len(runs))
    if len(tracks) > MAX_ODOMETRY_TRACKS:
        for track in tracks:
            track.odom = []
        result.notices.append(f"{len(tracks)} paths: odometry (dashed) is left out above {MAX_ODOMETRY_TRACKS}")
    plan = _plan(runs[0] / "scenario.yaml", result.notices)
    world = plan.world if plan is not None else None
    if plan is not None and not prefix:
        _sweep(plan, tracks)
    record = RunRecord.load(runs[0])
    title = record.scenario if record else folder.name
    if prefix:
        subtitle = f"sweep: {len(runs)} runs, {len(tracks)} paths"
    else:
        subtitle = (f"{record.sim_time:g} s simulated; " if record else "") + \
            f"{len(tracks)} robot{'s' if len(tracks) != 1 else ''}"
    result.out.parent.mkdir(parents=True, exist_ok=True)
    draw([drawn(t.label, t.true, t.odom, t.start_z, sweeps=t.swept) for t in tracks], world, result.out, title,
         subtitle)
    return result


def read_tracks(run: Path) -> list[_Points]:
    """Each odom CSV of a run folder as a track; odometry mapped into the world like the run does."""
    from mobot_cli.record.trajectory import odom_to_world

    tracks = []
    for path in sorted((run / "odom").glob("*.csv")):
        track, to_world = _Points(path.stem), None
        with path.open(encoding="utf-8", newline="") as f:
            for row in csv.DictReader(f):
                try:
                    state = _State(*(float(row[k]) for k in _State.FIELDS))
                except (KeyError, TypeError, ValueError):
                    continue  # a row cut short by a killed run
                if to_world is None:
                    to_world, track.start_z = odom_to_world(state), state.true_z
                track.true.append((state.true_x, state.true_y))
                track.odom.append(to_world(state.odom_x, state.odom_y))
                track.yaw.append(state.true_yaw)
        if track.true:
            tracks.append(track)
    return tracks


@dataclass
class _State:
    """The CSV columns odom_to_world and the plot use."""

    FIELDS = ("true_x", "true_y", "true_yaw", "odom_x", "odom_y", "odom_yaw", "true_z")
    true_x: float
    true_y: float
    true_yaw: float
    odom_x: float
    odom_y: float
    odom_yaw: float
    true_z: float


def _swept_values(folder: Path) -> dict[str, str]:
    """Each run folder's swept values from sweep.json, e.g. {"0001": "yaw=0.5"}."""
    runs = (_read_json(folder / "sweep.json") or {}).get("runs")
    values = {}
    for run in runs if isinstance(runs, list) else []:
        try:
            values[Path(run["folder"]).name] = " ".join(
                f"{key.rsplit('.', 1)[-1]}={value}" for key, value in run.get("params", {}).items())
        except (KeyError, TypeError, AttributeError):
            continue
    return values


def _sweep(plan, tracks: list[_Points]) -> None:
    """Sweep each robot's footprint over the areas of its coverage goals and checks, as the run did."""
    from mobot_cli.timeline.coverage import Sweep
    from mobot_cli.timeline.expect_time import coverage_areas

    areas = coverage_areas(plan)
    footprints = {r.name: r.footprint for r in (*plan.robots, *(e.spawn for e in plan.events if e.spawn))}
    for track in tracks:
        name = track.label.split("__")[0]  # a name used again in a live world: <name>__2
        for area in [*areas.get(name, ()), *areas.get("all", ())]:
            sweep = Sweep(area, plan.world, footprints.get(name))
            for (x, y), yaw in zip(track.true, track.yaw):
                sweep.add(x, y, yaw)
            track.swept.append(sweep)


def _plan(scenario: Path, notices: list[str]):
    """The run's plan, resolved again from its scenario.yaml; None (no floor plan) if that fails."""
    from mobot_cli.scenario.prepare import prepare

    if not scenario.is_file():
        notices.append(f"{scenario} is missing: drawn without the floor plan")
        return None
    try:
        return prepare(scenario).plan
    except MobotError as exc:
        notices.append(f"drawn without the floor plan: {exc}")
        return None


def _read_json(path: Path):
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
