"""A run folder read back for the view: the plan, each robot's time series, joint states, readings.

The world and the robots' URDF come from the resolved scenario.yaml (prepared again, as `mobot
plot` does); paths from odom/*.csv; joint angles (wheels turning) and sensor readings from the bag
when the run recorded one; the record from summary.json. Whatever is missing is left out with a
notice: a folder that still has its CSV files can be viewed.
"""

from __future__ import annotations

import csv
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mobot_cli.errors import Location, MobotError, UsageError
from mobot_cli.plan import Plan, RobotPlan
from mobot_cli.record.bagtopics import Joints
from mobot_cli.record.reader import (
    NOT_A_RUN_HINT,
    RunFolder,
    RunFolderError,
    is_run_folder,
    is_sweep_folder,
    sweep_runs,
)
from mobot_cli.record.summary import RunRecord
from mobot_cli.view.readings import Cloud

TRUE = ("true_x", "true_y", "true_z", "true_roll", "true_pitch", "true_yaw")
ODOM = ("odom_x", "odom_y", "odom_yaw")
_LIFE = re.compile(r"^(.*)__(\d+)$")  # a name used again in a live world: "<name>__2"


@dataclass
class Track:
    """One robot's life in the run: its rows, its model and what its sensors saw."""

    name: str
    t: np.ndarray  # (n,) seconds
    true: np.ndarray  # (n, 6) x, y, z, roll, pitch, yaw
    odom: np.ndarray  # (n, 2) odometry position mapped into the world
    odom_error: np.ndarray  # (n,) m
    cmd: np.ndarray  # (n, 2) linear, angular
    urdf: str | None = None
    frame_prefix: str = ""
    namespace: str = ""
    collisions: int | None = None  # from summary.json: the count at the end of its life
    joints: Joints | None = None
    readings: list[tuple[float, Cloud]] = field(default_factory=list)  # in time order

    def index(self, t: float) -> int | None:
        """The row shown at time ``t``; None before the robot's first row or after its last."""
        if not len(self.t) or t < self.t[0] - 1e-9 or t > self.t[-1] + 1e-9:
            return None
        return max(0, int(np.searchsorted(self.t, t, side="right")) - 1)


@dataclass
class RunView:
    """Everything `mobot view` draws of one run folder."""

    folder: Path
    plan: Plan | None
    record: RunRecord | None
    tracks: list[Track]
    duration: float
    log_rate_hz: float
    notices: list[str] = field(default_factory=list)
    # movers.csv (docs/movers.md): name -> (times (n,), x, y, yaw (n, 3)), in the order they came
    movers: dict[str, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)

    def movers_at(self, t: float) -> dict[str, tuple[float, float, float]]:
        """Each mover's pose at time ``t``: its last row at or before it (none before its first
        row, nor after its last row when it left before the end)."""
        out = {}
        for name, (times, poses) in self.movers.items():
            if t < times[0] - 1e-9 or (t > times[-1] + 1e-9 and times[-1] < self.last_mover_row - 1e-9):
                continue
            i = max(0, int(np.searchsorted(times, t, side="right")) - 1)
            out[name] = tuple(poses[i].tolist())
        return out

    @property
    def last_mover_row(self) -> float:
        return max((float(times[-1]) for times, _ in self.movers.values()), default=0.0)


def runs_of(folder: Path) -> list[Path]:
    """The run folders to offer: the folder itself, or each run of a sweep folder."""
    if is_sweep_folder(folder):
        runs = sweep_runs(folder)
        if runs:
            return runs
    elif is_run_folder(folder):
        return [folder]
    raise UsageError(f"'{folder}' is neither a run folder nor a sweep folder with runs", hint=NOT_A_RUN_HINT)


def read_run(folder: Path, plan: Plan | None = None) -> RunView:
    """Read one run folder for the view (UsageError when it has no odometry to show).

    ``plan``: the plan the run was made from, when this process made it (`mobot run --view`): the
    user's own scenario is not resolved again, confined, as an untrusted folder's is."""
    notices: list[str] = []
    run = RunFolder.open(folder)
    record = run.summary()
    tracks = [t for t in (_track(run, p) for p in run.odometry()) if t]
    if not tracks:
        raise UsageError(f"'{folder}' holds no odometry rows to show",
                         hint="Record with log.formats including csv, and let the run start.")
    plan = plan or run.plan(notices, "no world, and robots drawn as boxes")
    _attach(tracks, _robot_plans(plan), record)
    bag = run.bag_folder()
    if bag is not None and (bag / "metadata.yaml").is_file():
        _read_bag(bag, tracks, notices)
    elif bag is not None:
        notices.append(f"{bag} was not closed (no metadata.yaml): wheels are drawn without turning")
    movers = _movers(folder / "movers.csv", notices)
    duration = max(float(t.t[-1]) for t in tracks)
    rate = record.log_rate_hz if record else 1.0 / max(float(np.median(np.diff(tracks[0].t))), 1e-3) \
        if len(tracks[0].t) > 1 else 1.0
    return RunView(folder, plan, record, tracks, duration, rate, notices, movers)


def _movers(path: Path, notices: list[str]) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """movers.csv as arrays per mover; {} without the file, or with a notice when it is unreadable."""
    if not path.is_file():
        return {}
    rows: dict[str, list[tuple[float, float, float, float]]] = {}
    try:
        with path.open(newline="", encoding="utf-8") as f:
            for row in csv.DictReader(f):
                rows.setdefault(str(row["name"]), []).append(
                    (float(row["t"]), float(row["x"]), float(row["y"]), float(row["yaw"])))
    except (OSError, KeyError, TypeError, ValueError, csv.Error, UnicodeDecodeError) as exc:
        notices.append(f"{path} cannot be read ({exc}): movers are not shown")
        return {}
    return {name: (np.array([r[0] for r in got]), np.array([r[1:] for r in got]))
            for name, got in rows.items()}


def _robot_plans(plan: Plan | None) -> dict[str, RobotPlan]:
    if plan is None:
        return {}
    spawned = [e.spawn for e in plan.events if e.spawn is not None]
    return {r.name: r for r in (*plan.robots, *spawned)}


def _track(run: RunFolder, path: Path) -> Track | None:
    columns, rows = run.numeric_rows(path)
    if not rows or not {"t", *TRUE, *ODOM, "cmd_linear", "cmd_angular"} <= set(columns):
        return None
    a = np.array(rows)
    col = {name: i for i, name in enumerate(columns)}
    t, true = a[:, col["t"]], a[:, [col[k] for k in TRUE]]
    ox, oy, oyaw = (a[:, col[k]] for k in ODOM)
    # The odom frame is the first row's true pose (the spawn pose), as summary.json's odom_error.
    c, s = np.cos(true[0, 5] - oyaw[0]), np.sin(true[0, 5] - oyaw[0])
    x0 = true[0, 0] - (c * ox[0] - s * oy[0])
    y0 = true[0, 1] - (s * ox[0] + c * oy[0])
    odom = np.stack([x0 + c * ox - s * oy, y0 + s * ox + c * oy], axis=1)
    name = path.stem
    return Track(name, t, true, odom, np.hypot(*(odom - true[:, :2]).T),
                 a[:, [col["cmd_linear"], col["cmd_angular"]]])


def _attach(tracks: list[Track], robots: dict[str, RobotPlan], record: RunRecord | None) -> None:
    """Each track's model and frames from the plan; the record's namespace wins, as the run wrote it."""
    for track in tracks:
        match = _LIFE.match(track.name)
        plan = robots.get(track.name) or (robots.get(match.group(1)) if match else None)
        robot_record = record.robots.get(track.name) if record else None
        if plan is not None:
            track.urdf, track.frame_prefix, track.namespace = plan.urdf, plan.frame_prefix, plan.namespace
        if robot_record is not None:
            track.collisions, track.namespace = robot_record.collisions, robot_record.namespace
            track.frame_prefix = track.frame_prefix or robot_record.namespace.strip("/") + "/"


def _read_bag(bag: Path, tracks: list[Track], notices: list[str]) -> None:
    """Joint states, robot descriptions and sensor readings per namespace, from the rosbag2 folder."""
    from mobot_cli.record.bagtopics import read_topics

    by_ns: dict[str, list[Track]] = {}
    for track in tracks:
        by_ns.setdefault(track.namespace, []).append(track)
    try:
        topics = read_topics(bag, set(by_ns))
    except MobotError as exc:  # a closed bag that does not read is damaged: refused like any damaged file
        raise RunFolderError(f"bag/ does not read ({exc})", location=Location(file=bag.parent),
                             hint="The run folder is damaged or was not written by mobot.") from None
    _attach_topics(topics, by_ns, _roots(bag.parent))


def _attach_topics(topics: dict, by_ns: dict[str, list[Track]], roots: tuple[Path, ...]) -> None:
    for ns, found in topics.items():
        for track in by_ns.get(ns, ()):
            track.joints = found.joints
            track.urdf = track.urdf or _drawable(found.description, roots)
            prefix = track.frame_prefix
            track.readings = [(t, Cloud(track.name, sensor, frame[len(prefix):] if frame.startswith(prefix)
                                        else frame, points)) for t, sensor, frame, points in found.readings
                              if track.t[0] - 1e-9 <= t <= track.t[-1] + 1e-9]


def _roots(folder: Path) -> tuple[Path, ...]:
    from mobot_cli.assets.resources import ResourceResolver

    return (folder.resolve(), *ResourceResolver(folder).roots)


def _drawable(urdf: str | None, roots: tuple[Path, ...]) -> str | None:
    """A bag's robot_description, when every mesh it names is a regular file the run folder's
    scenario could have named (inside the folder or the resource search path); else None (a box)."""
    if urdf is None:
        return None
    for name in re.findall(r'filename="([^"]*)"', urdf):
        path = Path(name.removeprefix("file://"))
        try:
            resolved = path.resolve(strict=True)
        except (OSError, RuntimeError):
            return None
        if not resolved.is_file() or not any(resolved.is_relative_to(root) for root in roots):
            return None
    return urdf
