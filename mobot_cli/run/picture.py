"""Drawing trajectory.png from plain tracks: what a run's helper process imports (run/ahead.py),
without the engine, which the trajectory sink (run/trajectory.py) sits on."""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

from mobot_cli.sim.plan import WorldPlan


class Drawn(NamedTuple):
    """One robot's track as the picture takes it: plain values, so that another process can draw
    it (run/ahead.py). ``swept`` holds (x0, y0, cell, covered mask, area) per coverage area."""

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


def preload(one_picture: bool = False) -> None:
    """Import the drawing code and load its fonts now (a sweep's fork server, once for its workers);
    ``one_picture``: and make ready the memory of the one picture this process draws next."""
    from mobot_cli.plot.render import preload as preload_render

    preload_render(one_picture)


def draw(tracks: list[Drawn], world: WorldPlan | None, out: Path, title: str, subtitle: str) -> None:
    """Render ``tracks`` over ``world``'s floor plan to ``out``; the plan's height band is measured
    from the floor where the tracks start."""
    from mobot_cli.assets.world.floorplan import floor_plan
    from mobot_cli.plot.render import Swept, Track, render

    labels = [t.label for t in tracks]
    plot_tracks = [Track(_unique(t.label, labels[:i]), t.true, t.odom, t.scan,
                         [Swept(x0, y0, cell, covered, list(area)) for x0, y0, cell, covered, area in t.swept])
                   for i, t in enumerate(tracks)]
    starts = [(*t.true[0], t.start_z) for t in tracks if t.true and t.start_z is not None]
    render(plot_tracks, floor_plan(world, starts) if world is not None else [], out, title, subtitle)


def _unique(label: str, before: list[str]) -> str:
    count = before.count(label)
    return f"{label} ({count + 1})" if count else label
