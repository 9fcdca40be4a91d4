"""Timing helpers shared by the bench scripts (run them as `python3 bench/NAME.py`)."""

from __future__ import annotations

import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


def timed(fn, *args) -> tuple[float, float]:
    """(wall, CPU) seconds of one call; CPU time is steadier on a shared machine."""
    wall, cpu = time.perf_counter(), time.process_time()
    fn(*args)
    return time.perf_counter() - wall, time.process_time() - cpu


def process_seconds(args: list[str], repeat: int, env: dict | None = None) -> float:
    """Median wall seconds of a whole command, start-up included."""
    times = []
    for _ in range(repeat):
        started = time.perf_counter()
        subprocess.run(args, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
        times.append(time.perf_counter() - started)
    return statistics.median(times)


def bytecode_state(tree: Path) -> str:
    """Whether ``tree``'s mobot modules load from cached bytecode, which decides ~0.1 s of a
    process's start: a wheel's install compiles them, and so does any run without
    PYTHONDONTWRITEBYTECODE; a checkout on a machine that sets it compiles them in every process."""
    import importlib.util
    import os

    cached = Path(importlib.util.cache_from_source(str(Path(tree) / "mobot_cli" / "run.py"))).exists()
    state = "bytecode cached" if cached else "no cached bytecode: every process compiles them again"
    if os.environ.get("PYTHONDONTWRITEBYTECODE"):
        state += "; PYTHONDONTWRITEBYTECODE is set (`python3 -m compileall -q mobot_cli` caches it)"
    return state


class Server:
    """`mobot serve` in a subprocess with its own socket and cache folder (bench_live, bench_hostile)."""

    def __init__(self, *args: str, cache: Path):
        from mobot_cli.errors import LiveWorldError
        from mobot_cli.live.client import Client

        self.folder = Path(tempfile.mkdtemp(prefix="mobot-b-"))
        self.endpoint = f"ipc://{self.folder / 's.sock'}"
        env = {**os.environ, "MOBOT_CACHE_DIR": str(cache)}
        self.process = subprocess.Popen([sys.executable, "-m", "mobot_cli", "serve", *args, "--quiet",
                                         "--endpoint", self.endpoint], cwd=REPO, env=env)
        deadline = time.monotonic() + 120  # a busy machine starts it slowly
        while True:
            try:
                with Client(self.endpoint, timeout=0.5) as client:
                    client.ping()
                return
            except LiveWorldError:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.05)

    def stop(self) -> None:
        from mobot_cli.live.client import Client

        with Client(self.endpoint, timeout=60) as client:
            client.stop()
        self.process.wait(60)
