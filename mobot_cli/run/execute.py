"""`mobot run` without the printing: plan in, run folder out, summary returned."""

from __future__ import annotations

import itertools
import math
import platform
import time
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path
from typing import Any, Callable, Optional

from mobot_cli import __version__
from mobot_cli.errors import MobotError
from mobot_cli.run.expect import Checker, Result, summary_block
from mobot_cli.run.sinks import make_sinks, write_json_atomic, write_text_atomic
from mobot_cli.run.timeline import simulate
from mobot_cli.sim.plan import Plan
from mobot_cli.sim.state import RobotState

Progress = Callable[[int, int], None]


@dataclass
class Track:
    """What the summary needs to know of one robot, accumulated sample by sample."""

    first: Optional[RobotState] = None
    last: Optional[RobotState] = None
    distance: float = 0.0

    def add(self, state: RobotState) -> None:
        if self.first is None:
            self.first = state
        elif self.last is not None:
            self.distance += math.hypot(state.true_x - self.last.true_x, state.true_y - self.last.true_y)
        self.last = state

    def summary(self) -> dict[str, Any]:
        s, o = self.last, self.first
        # odom_* is relative to the spawn pose: map it into the world to compare with the truth.
        c, n = math.cos(o.true_yaw), math.sin(o.true_yaw)
        ox = o.true_x + c * s.odom_x - n * s.odom_y
        oy = o.true_y + n * s.odom_x + c * s.odom_y
        yaw_error = math.remainder(o.true_yaw + s.odom_yaw - s.true_yaw, math.tau)
        return {
            "final_pose": {"x": _r(s.true_x), "y": _r(s.true_y), "z": _r(s.true_z), "roll": _r(s.true_roll),
                           "pitch": _r(s.true_pitch), "yaw": _r(s.true_yaw)},
            "final_odom": {"x": _r(s.odom_x), "y": _r(s.odom_y), "yaw": _r(s.odom_yaw)},
            "distance": _r(self.distance),
            "collisions": s.collisions,
            "odom_error": {"position": _r(math.hypot(ox - s.true_x, oy - s.true_y)), "yaw": _r(yaw_error)},
        }


@dataclass
class RunResult:
    """The outcome of one run; ``summary`` is what summary.json holds."""

    out_dir: Path
    summary: dict[str, Any] = field(default_factory=dict)
    expectations: list[Result] = field(default_factory=list)  # empty when the run did not finish


def execute(plan: Plan, resolved_yaml: str, out_dir: Path, progress: Progress | None = None) -> RunResult:
    """Run a plan and write its run folder; summary.json is written last and says how it ended."""
    # The first sample comes after the world is built and the robots are spawned and checked:
    # a spawn refused (inside furniture, below the floor) leaves no run folder behind.
    samples = simulate(plan)
    first = next(samples)
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / "summary.json").unlink(missing_ok=True)  # a rerun must not look complete early
    write_text_atomic(out_dir / "scenario.yaml", resolved_yaml)
    tracks: dict[str, Track] = {}
    sinks = make_sinks(plan, out_dir)
    checker = Checker(plan)
    sinks.append(checker)
    results: list[Result] = []
    status, error, last_step = "ok", None, 0
    started = time.perf_counter()
    try:
        for sample in itertools.chain([first], samples):
            for sink in sinks:
                sink.write(sample)
            for name, state in sample.states.items():
                tracks.setdefault(name, Track()).add(state)
            last_step = sample.step
            if progress:
                progress(sample.step, plan.total_steps)
    except MobotError as exc:
        status, error = "fault", exc
        raise
    except KeyboardInterrupt:
        status = "interrupted"
        raise
    except Exception as exc:  # a bug, not bad input: summary.json must still not say "ok"
        status, error = "error", exc
        raise
    finally:
        samples.close()
        for sink in sinks:
            sink.close()
        wall = time.perf_counter() - started
        summary = _summary(plan, tracks, status, error, last_step, wall)
        if plan.expectations and status == "ok":
            results = checker.results()
            summary["expectations"] = summary_block(results)
        write_json_atomic(out_dir / "summary.json", summary)
    return RunResult(out_dir=out_dir, summary=summary, expectations=results)


def _summary(plan: Plan, tracks: dict[str, Track], status: str, error: Exception | None,
             last_step: int, wall: float) -> dict[str, Any]:
    sim_time = last_step / plan.physics.rate_hz
    return {
        "status": status,
        "error": str(error) if error else None,
        "scenario": plan.name,
        "seed": plan.seed,
        "versions": {"mobot": __version__, "pybullet": _version("pybullet"), "python": platform.python_version()},
        "steps": last_step,
        "sim_time": _r(sim_time),
        "wall_time": round(wall, 3),
        "real_time_factor": round(sim_time / wall, 2) if wall > 0 else None,
        "physics_rate_hz": plan.physics.rate_hz,
        "log_rate_hz": _r(plan.physics.rate_hz / plan.log_every),
        "notices": list(plan.notices),
        "robots": {name: track.summary() for name, track in tracks.items() if track.last is not None},
    }


def _version(package: str) -> str | None:
    try:
        return metadata.version(package)
    except metadata.PackageNotFoundError:
        return None


def _r(value: float) -> float:
    return round(value, 6) + 0.0
