#!/usr/bin/env python3
"""What does the rosbag2/MCAP log cost? Wall-time ratio of [csv, mcap] to [csv] runs.

For 1 and 10 bundled robots driving circles, logged at 50 Hz, it times ``execute`` (the whole
run: world, timeline, sinks, trajectory.png, summary) with ``formats: [csv]`` and with
``formats: [csv, mcap]``, alternating the two, in one process (imports warm after the first
repeat). It shows medians of wall and CPU time (CPU time is steadier on a shared machine) and
the time spent inside the bag sink itself ("in sink"; 1 + in sink / csv is the ratio that
the bag alone adds). Then it times whole ``mobot run`` processes for 10 simulated seconds
with and without the bag (cold imports included).

    python3 bench/bench_bag.py [--seconds 20] [--repeat 5]
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from common import process_seconds, timed  # noqa: E402  (bench/common.py)

from mobot_cli.run import execute  # noqa: E402
from mobot_cli.scenario.prepare import prepare  # noqa: E402


def scenario_text(robots: int, seconds: float, formats: str) -> str:
    """N bundled robots 1 m apart, each driving a circle after settling, logged at 50 Hz."""
    poses = ", ".join(f"[{(i % 5) * 1.0}, {(i // 5) * 1.0}, 0]" for i in range(robots))
    return (f"version: 1\nname: bag{robots}\nduration: {seconds}\nsettle: 0.5\n"
            f"physics: {{rate_hz: 250, solver_iterations: 50}}\nlog: {{rate_hz: 50, formats: [{formats}]}}\n"
            f"robots:\n  - name: r_{{i}}\n    count: {robots}\n    poses: [{poses}]\n"
            f"    commands: [{{at: 0.5, linear: 0.3, angular: 0.3}}]\n")


class SinkClock:
    """Seconds spent inside BagSink (open, write, close): the bag's own cost, measured in the run."""

    def __init__(self) -> None:
        from mobot_cli.record import bag

        self.seconds = 0.0
        for name in ("__init__", "write", "close"):
            original = getattr(bag.BagSink, name)

            def wrapped(*args, _original=original, **kwargs):
                started = time.perf_counter()
                try:
                    return _original(*args, **kwargs)
                finally:
                    self.seconds += time.perf_counter() - started

            setattr(bag.BagSink, name, wrapped)


def run_once(prepared, out: Path) -> None:
    execute(prepared.plan, prepared.resolved_yaml, out)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=20.0, help="simulated seconds per run")
    parser.add_argument("--repeat", type=int, default=5, help="runs per figure (the median is shown)")
    args = parser.parse_args()
    work = Path(tempfile.mkdtemp(prefix="mobot-bench-bag-"))
    try:
        print(f"[csv, mcap] vs [csv], {args.seconds:g} simulated s at 250 Hz, log 50 Hz, in-process execute()")
        print(f"{'robots':>6} {'csv s':>8} {'+mcap s':>8} {'ratio':>6} {'csv cpu':>8} {'+mcap cpu':>9} "
              f"{'ratio':>6} {'in sink':>8} {'1+sink/csv':>10} {'bag MB':>7} {'messages':>9}")
        clock = SinkClock()
        for robots in (1, 10):
            plans = {}
            for label, formats in (("csv", "csv"), ("mcap", "csv, mcap")):
                path = work / f"{label}{robots}.yaml"
                path.write_text(scenario_text(robots, args.seconds, formats))
                plans[label] = prepare(path)
            times: dict[str, list[tuple[float, float]]] = {"csv": [], "mcap": []}
            in_sink = []
            for i in range(args.repeat):
                for label in ("csv", "mcap") if i % 2 == 0 else ("mcap", "csv"):
                    clock.seconds = 0.0
                    times[label].append(timed(run_once, plans[label], work / f"{label}{robots}-{i}"))
                    if label == "mcap":
                        in_sink.append(clock.seconds)
            sink = statistics.median(in_sink)
            csv_s, mcap_s = (statistics.median(w for w, _ in times[k]) for k in ("csv", "mcap"))
            csv_c, mcap_c = (statistics.median(c for _, c in times[k]) for k in ("csv", "mcap"))
            bag = work / f"mcap{robots}-0" / "bag"
            size = sum(f.stat().st_size for f in bag.iterdir()) / 1e6
            count = next(line for line in (bag / "metadata.yaml").read_text().splitlines()
                         if line.strip().startswith("message_count")).split(":")[1].strip()
            print(f"{robots:>6} {csv_s:>8.3f} {mcap_s:>8.3f} {mcap_s / csv_s:>6.3f} {csv_c:>8.3f} {mcap_c:>9.3f} "
                  f"{mcap_c / csv_c:>6.3f} {sink:>8.3f} {1 + sink / csv_s:>10.3f} {size:>7.2f} {count:>9}")
        mobot = str(Path(sys.executable).parent / "mobot")
        mobot = mobot if Path(mobot).exists() else (shutil.which("mobot") or "mobot")
        for label, formats in (("csv", "csv"), ("mcap", "csv, mcap")):
            path = work / f"ten-{label}.yaml"
            path.write_text(scenario_text(1, 10.0, formats))
            subprocess.run([mobot, "run", str(path), "--out", str(work / "warm"), "--quiet"], check=True)
            t = process_seconds([mobot, "run", str(path), "--out", str(work / f"ten-{label}"), "--quiet"],
                                args.repeat)
            print(f"mobot run, 10 simulated s, [{formats}], whole process: {t:.3f} s")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
