"""Timing helpers shared by the bench scripts (run them as `python3 bench/NAME.py`)."""

from __future__ import annotations

import statistics
import subprocess
import time


def timed(fn, *args) -> tuple[float, float]:
    """(wall, CPU) seconds of one call; CPU time is steadier on a shared machine."""
    wall, cpu = time.perf_counter(), time.process_time()
    fn(*args)
    return time.perf_counter() - wall, time.process_time() - cpu


def process_seconds(args: list[str], repeat: int) -> float:
    """Median wall seconds of a whole command, start-up included."""
    times = []
    for _ in range(repeat):
        started = time.perf_counter()
        subprocess.run(args, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        times.append(time.perf_counter() - started)
    return statistics.median(times)
