"""``DIR/trajectory.png``: every robot's true path and odometry over the floor plan, after every run,
with each lidar robot's last scan as points.

The sink only collects points while the run goes; the plotting code (Pillow, and trimesh for
mesh worlds) is imported when the picture is drawn, at close.
"""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

from mobot_cli.common.transforms import Planar, odom_origin
from mobot_cli.plan import Plan, WorldPlan
from mobot_cli.record.sinks import named
from mobot_cli.sim.state import RobotState
from mobot_cli.timeline.records import Reading, Sample, Sink

MOVER_SPACING = 0.1  # m (in x plus y) between two points of a mover's path in the picture
SCAN_BAND = (0.05, 2.0)  # m above the floor: a 3D lidar's returns drawn on the floor plan
MAX_SCAN_POINTS = 20000


def odom_to_world(state: RobotState) -> Planar:
    """Maps a robot's odometry into the world: its odom frame is where odometry started.

    Taken at the robot's first sample, whenever that is: exact then.
    """
    return odom_origin(state.true_x, state.true_y, state.true_yaw,
                       state.odom_x, state.odom_y, state.odom_yaw)


class TrajectorySink(Sink):
    """Collects each robot's path; close() draws ``trajectory.png``."""

    def __init__(self, plan: Plan, out_dir: Path, sweeps: dict | None = None):
        self.path = out_dir / "trajectory.png"
        self.sweeps = sweeps if sweeps is not None else {}  # (robot, area) -> run.sweep.Sweep, filled meanwhile
        self.world = plan.world
        self.title = plan.name
        self.rate = plan.physics.rate_hz
        self.tracks: list = []  # plot.render.Track, created lazily to keep Pillow out of the run
        self.open: dict[str, tuple[object, Planar]] = {}
        self.last_step = 0
        self.movers: dict[str, list[tuple[float, float]]] = {}  # mover name -> its path (docs/movers.md)

    def deleted(self, step: int, key: str) -> None:
        self.open.pop(key, None)

    def write(self, sample: Sample) -> None:
        for name, state in sample.states.items():
            entry = self.open.get(name)
            if entry is None:
                entry = self.open[name] = (_Points(name), odom_to_world(state))
                entry[0].start_z = state.true_z
                self.tracks.append(entry[0])
            points, to_world = entry
            points.true.append((state.true_x, state.true_y))
            points.odom.append(to_world(state.odom_x, state.odom_y))
        if sample.movers:
            for name, (x, y, _) in sample.movers.items():
                path = self.movers.setdefault(name, [])
                # a point every MOVER_SPACING: fifty walkers' paths drawn with no more points than needed
                if not path or abs(x - path[-1][0]) + abs(y - path[-1][1]) >= MOVER_SPACING:
                    path.append((x, y))
        self.last_step = sample.step

    def reading(self, key: str, reading: Reading) -> None:
        """Keep each robot's last lidar scan; its points are made when the picture is drawn."""
        if reading.sensor.kind == "lidar" and key in self.open:
            self.open[key][0].last_scan = reading.data

    def close(self) -> None:
        try:
            draw(self._tracks(), self.world, self.path, self.title, self._subtitle())
        except OSError as exc:  # written atomically: no half a picture is left
            raise named(exc, self.path) from None

    def _tracks(self) -> list[Drawn]:
        robots = [drawn(t.label, t.true, t.odom, t.start_z, t.scan,
                        [s for (name, _), s in self.sweeps.items() if name == t.label]) for t in self.tracks]
        return robots + [drawn(f"mover {name}", path, [], None) for name, path in self.movers.items()]

    def _subtitle(self) -> str:
        return f"{self.last_step / self.rate:g} s simulated; {_robots(len(self.tracks))}"


class _Points:
    """A track's points as they come (the plot's Track is made at drawing time)."""

    def __init__(self, label: str):
        self.label, self.true, self.odom = label, [], []
        self.last_scan = None  # sim.sensors.ScanData
        self.start_z: float | None = None  # the root link's height where the path starts

    @property
    def scan(self) -> list[tuple[float, float]]:
        """The last scan's returns in world x, y (a 3D lidar's within the floor plan's band)."""
        if self.last_scan is None:
            return []
        points = self.last_scan.world_points()
        if self.last_scan.ranges.shape[0] > 1:  # a 3D lidar: what a floor plan shows, not the floor
            points = points[(points[:, 2] > SCAN_BAND[0]) & (points[:, 2] < SCAN_BAND[1])]
        return [tuple(xy) for xy in points[::max(1, len(points) // MAX_SCAN_POINTS), :2].tolist()]


class Drawn(NamedTuple):
    """One robot's track as the picture takes it, from a run or from a run folder's CSV files
    (record/replot.py). ``swept`` holds (x0, y0, cell, covered mask, area) per coverage area."""

    label: str
    true: list
    odom: list
    start_z: float | None
    scan: list
    swept: list


def drawn(label: str, true: list, odom: list, start_z: float | None, scan: list = (), sweeps=()) -> Drawn:
    """A track as the picture takes it; ``sweeps`` are run.sweep.Sweep objects."""
    return Drawn(label, true, odom, start_z, list(scan),
                 [(s.grid.x0, s.grid.y0, s.grid.cell, s.covered, s.area) for s in sweeps])


def preload() -> None:
    """Import the drawing code and load its fonts now (a sweep's fork server, once for its workers)."""
    from mobot_cli.record.render import preload as preload_render

    preload_render()


def draw(tracks: list[Drawn], world: WorldPlan | None, out: Path, title: str, subtitle: str) -> None:
    """Render ``tracks`` over ``world``'s floor plan to ``out``; the plan's height band is measured
    from the floor where the tracks start."""
    from mobot_cli.assets.world.floorplan import floor_parts
    from mobot_cli.record.render import Swept, Track, render

    labels = [t.label for t in tracks]
    plot_tracks = [Track(_unique(t.label, labels[:i]), t.true, t.odom, t.scan,
                         [Swept(x0, y0, cell, covered, list(area)) for x0, y0, cell, covered, area in t.swept])
                   for i, t in enumerate(tracks)]
    starts = [(*t.true[0], t.start_z) for t in tracks if t.true and t.start_z is not None]
    render(plot_tracks, floor_parts(world, starts) if world is not None else [], out, title, subtitle)


def _unique(label: str, before: list[str]) -> str:
    count = before.count(label)
    return f"{label} ({count + 1})" if count else label


def _robots(n: int) -> str:
    return f"{n} robot{'s' if n != 1 else ''}"
