"""The record of a live world (`mobot serve --out DIR`), laid out like `mobot run`'s folder.

    DIR/scenario.yaml      the resolved world (and scenario) the server started from
    DIR/history.jsonl      one line per spawn, delete, cmd and scripted event, refused ones too
    DIR/odom/<robot>.csv   as in a run folder; a name used again after a delete gets <robot>__2.csv
    DIR/summary.json       written last, when the server stops (also on SIGINT/SIGTERM)
"""

from __future__ import annotations

import json
import platform
import time
from pathlib import Path
from typing import Any

from mobot_cli import __version__
from mobot_cli.run.execute import Track
from mobot_cli.run.sinks import make_sinks, write_json_atomic, write_text_atomic
from mobot_cli.run.timeline import Sample
from mobot_cli.sim.plan import Plan


class Recorder:
    """Writes samples through the run sinks and keeps the history and per-robot tracks."""

    def __init__(self, out_dir: Path, plan: Plan, resolved_yaml: str):
        self.out_dir, self.plan = out_dir, plan
        out_dir.mkdir(parents=True, exist_ok=True)
        (out_dir / "summary.json").unlink(missing_ok=True)  # a reused folder must not look finished
        write_text_atomic(out_dir / "scenario.yaml", resolved_yaml)
        self._history = (out_dir / "history.jsonl").open("w", encoding="utf-8")
        self._sinks = make_sinks(plan, out_dir)
        self._keys: dict[str, str] = {}  # live name -> log name
        self._lives: dict[str, int] = {}
        self._tracks: dict[str, Track] = {}
        self._info: dict[str, dict[str, Any]] = {}
        self._started = time.perf_counter()

    def spawned(self, name: str, step: int, namespace: str, source: str) -> None:
        """A robot appeared; its rows go to odom/<name>.csv (or <name>__N.csv for a reused name)."""
        lives = self._lives[name] = self._lives.get(name, 0) + 1
        key = name if lives == 1 else f"{name}__{lives}"
        self._keys[name] = key
        self._info[key] = {"name": name, "namespace": namespace, "source": source,
                           "spawned_at": step / self.plan.physics.rate_hz, "deleted_at": None}

    def deleted(self, name: str, step: int) -> None:
        """A robot left the world; its file keeps what it had."""
        key = self._keys.pop(name, None)
        if key is not None:
            self._info[key]["deleted_at"] = step / self.plan.physics.rate_hz

    def write(self, sample: Sample) -> None:
        """One sample of every robot, under its log name."""
        states = {self._keys.get(name, name): state for name, state in sample.states.items()}
        renamed = Sample(sample.step, states)
        for sink in self._sinks:
            sink.write(renamed)
        for key, state in states.items():
            self._tracks.setdefault(key, Track()).add(state)

    def history(self, step: int, record: dict[str, Any]) -> None:
        """One line of history, flushed at once (a killed server keeps what happened)."""
        line = {"t": step / self.plan.physics.rate_hz, "step": step, **record}
        self._history.write(json.dumps(line, allow_nan=False, default=str) + "\n")
        self._history.flush()

    def close(self, status: str, error: str | None, steps: int, extra: dict[str, Any]) -> dict[str, Any]:
        """Close every file and write summary.json last; returns the summary."""
        for sink in self._sinks:
            sink.close()
        self._history.close()
        wall = time.perf_counter() - self._started
        sim_time = steps / self.plan.physics.rate_hz
        robots = {key: {**self._info.get(key, {}), **track.summary()}
                  for key, track in self._tracks.items() if track.last is not None}
        summary = {
            "status": status, "error": error, "scenario": self.plan.name, "world": self.plan.world.name,
            "seed": self.plan.seed,
            "versions": {"mobot": __version__, "python": platform.python_version()},
            "steps": steps, "sim_time": round(sim_time, 6), "wall_time": round(wall, 3),
            "real_time_factor": round(sim_time / wall, 2) if wall > 0 else None,
            "physics_rate_hz": self.plan.physics.rate_hz,
            "log_rate_hz": round(self.plan.physics.rate_hz / self.plan.log_every, 6),
            **extra, "robots": robots,
        }
        write_json_atomic(self.out_dir / "summary.json", summary)
        return summary
