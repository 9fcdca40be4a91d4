"""``DIR/trajectory.png``: every robot's true path and odometry over the floor plan, after every run.

The sink only collects points while the run goes; the plotting code (Pillow, and trimesh for
mesh worlds) is imported when the picture is drawn, at close.
"""

from __future__ import annotations

from pathlib import Path

from mobot_cli.common.transforms import Planar, odom_origin
from mobot_cli.run.sinks import Sink
from mobot_cli.run.timeline import Sample
from mobot_cli.sim.plan import Plan, WorldPlan
from mobot_cli.sim.state import RobotState


def odom_to_world(state: RobotState) -> Planar:
    """Maps a robot's odometry into the world: its odom frame is where odometry started.

    Taken at the robot's first sample, whenever that is: exact then.
    """
    return odom_origin(state.true_x, state.true_y, state.true_yaw,
                       state.odom_x, state.odom_y, state.odom_yaw)


class TrajectorySink(Sink):
    """Collects each robot's path; close() draws ``trajectory.png``."""

    def __init__(self, plan: Plan, out_dir: Path):
        self.path = out_dir / "trajectory.png"
        self.world = plan.world
        self.title = plan.name
        self.rate = plan.physics.rate_hz
        self.tracks: list = []  # plot.render.Track, created lazily to keep Pillow out of the run
        self.open: dict[str, tuple[object, Planar]] = {}
        self.last_step = 0

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
        self.last_step = sample.step

    def close(self) -> None:
        draw(self.tracks, self.world, self.path, self.title,
             f"{self.last_step / self.rate:g} s simulated; {_robots(len(self.tracks))}")


class _Points:
    """A track's points as they come (the plot's Track is made at drawing time)."""

    def __init__(self, label: str):
        self.label, self.true, self.odom = label, [], []
        self.start_z: float | None = None  # the root link's height where the path starts


def draw(tracks: list, world: WorldPlan | None, out: Path, title: str, subtitle: str) -> None:
    """Render ``tracks`` (objects with label, true, odom, start_z) over ``world``'s floor plan to
    ``out``; the plan's height band is measured from the floor where the tracks start."""
    from mobot_cli.plot.floorplan import floor_plan
    from mobot_cli.plot.render import Track, render

    labels = [t.label for t in tracks]
    plot_tracks = [Track(_unique(t.label, labels[:i]), t.true, t.odom) for i, t in enumerate(tracks)]
    starts = [(*t.true[0], t.start_z) for t in tracks if t.true and t.start_z is not None]
    render(plot_tracks, floor_plan(world, starts) if world is not None else [], out, title, subtitle)


def _unique(label: str, before: list[str]) -> str:
    count = before.count(label)
    return f"{label} ({count + 1})" if count else label


def _robots(n: int) -> str:
    return f"{n} robot{'s' if n != 1 else ''}"
