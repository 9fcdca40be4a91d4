"""``mobot plot``: redraw trajectory.png from a run folder's CSV files, or overlay a sweep's runs."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from mobot_cli.errors import UsageError
from mobot_cli.record.reader import RunFolder, is_run_folder, is_sweep_folder, sweep_runs
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
        runs, prefix = [RunFolder.open(p) for p in sweep_runs(folder)], True
    elif is_run_folder(folder):
        runs, prefix = [RunFolder.open(folder)], False
    else:
        raise UsageError(f"'{folder}' is neither a run folder nor a sweep folder",
                         hint="Give the folder that mobot run --out or mobot sweep --out wrote.")
    params = _swept_values(folder) if prefix else {}
    tracks = []
    for run in runs:
        for track in read_tracks(run):
            if prefix:  # "0001/mobot (yaw=0.5)"
                name = run.path.name
                track.label = f"{name}/{track.label}" + (f" ({params[name]})" if params.get(name) else "")
            tracks.append(track)
    if not tracks:
        raise UsageError(f"'{folder}' holds no odometry CSV files to draw",
                         hint="Run with log.formats including csv, and let the run start.")
    result = PlotResult(out=out or folder / "trajectory.png", tracks=len(tracks), runs=len(runs))
    if len(tracks) > MAX_ODOMETRY_TRACKS:
        for track in tracks:
            track.odom = []
        result.notices.append(f"{len(tracks)} paths: odometry (dashed) is left out above {MAX_ODOMETRY_TRACKS}")
    plan = runs[0].plan(result.notices, "drawn without the floor plan")
    world = plan.world if plan is not None else None
    if plan is not None and not prefix:
        _sweep(plan, tracks)
    record = runs[0].summary()
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


def read_tracks(run: RunFolder) -> list[_Points]:
    """Each odom CSV of a run folder as a track; odometry mapped into the world like the run does."""
    from mobot_cli.record.trajectory import odom_to_world

    tracks = []
    for path in run.odometry():
        track, to_world = _Points(path.stem), None
        header, rows = run.numeric_rows(path)
        column = {name: i for i, name in enumerate(header)}
        if not set(_State.FIELDS) <= set(column):
            continue
        for row in rows:
            state = _State(*(row[column[k]] for k in _State.FIELDS))
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
    document = RunFolder(folder).json("sweep.json")
    runs = document.get("runs") if isinstance(document, dict) else None
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
