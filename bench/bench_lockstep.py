#!/usr/bin/env python3
"""How long does a lockstep `step` take, request to reply, over ipc?

Starts a real `mobot serve SCENARIO --paused --fast` process and, through the Python client
(the one `mobot step` uses), sends `step` requests of one physics step, each waiting for its
reply: the median and 90th percentile round trip over ``--requests`` requests, with every
robot's state in the reply (the default) and without it (``states: false``), plus `ping`
(no step, the floor of a round trip) and `get_state`. Rounds interleave the kinds, so a busy
machine slows them alike.

    python3 bench/bench_lockstep.py [--requests 3000] [--rounds 3] [--scenario scenarios/quickstart.yaml]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from mobot_cli.errors import LiveWorldError  # noqa: E402
from mobot_cli.live.client import Client  # noqa: E402

KINDS = {
    "step 1 (states)": ("step", {"steps": 1}),
    "step 1 (no states)": ("step", {"steps": 1, "states": False}),
    "get_state": ("get_state", {"name": "mobot"}),
    "ping": ("ping", {}),
}


def serve(scenario: str, cache: Path) -> tuple[subprocess.Popen, str]:
    folder = Path(tempfile.mkdtemp(prefix="mobot-b-"))
    endpoint = f"ipc://{folder / 's.sock'}"
    env = {**os.environ, "MOBOT_CACHE_DIR": str(cache)}
    process = subprocess.Popen([sys.executable, "-m", "mobot_cli", "serve", scenario, "--paused", "--fast",
                                "--quiet", "--endpoint", endpoint], cwd=REPO, env=env)
    deadline = time.monotonic() + 60
    while True:
        try:
            with Client(endpoint, timeout=0.5) as client:
                client.ping()
            return process, endpoint
        except LiveWorldError:
            if time.monotonic() > deadline:
                process.kill()
                raise
            time.sleep(0.05)


def round_trips(client: Client, op: str, fields: dict, count: int) -> list[float]:
    """Seconds from request to reply, ``count`` times."""
    out = []
    call, clock = client.call, time.perf_counter
    for _ in range(count):
        started = clock()
        reply = call(op, **fields)
        out.append(clock() - started)
        if not reply["ok"]:
            raise RuntimeError(f"{op} refused: {reply}")
    return out


def percentile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--requests", type=int, default=3000, help="requests per kind and round")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--scenario", default=str(REPO / "scenarios" / "quickstart.yaml"))
    args = parser.parse_args()
    cache = Path(tempfile.mkdtemp(prefix="mobot-b-cache-"))
    process, endpoint = serve(args.scenario, cache)
    times: dict[str, list[float]] = {kind: [] for kind in KINDS}
    try:
        with Client(endpoint, timeout=30) as client:
            for op, fields in KINDS.values():  # warm up every path once
                round_trips(client, op, fields, 200)
            for _ in range(args.rounds):
                for kind, (op, fields) in KINDS.items():
                    times[kind] += round_trips(client, op, fields, args.requests)
            steps = client.ping()["step"]
            client.stop()
        process.wait(30)
    finally:
        if process.poll() is None:
            process.kill()
    print(f"lockstep round trips over ipc, {args.rounds} x {args.requests} requests each "
          f"({Path(args.scenario).name}, {steps} steps taken):")
    for kind, values in times.items():
        print(f"  {kind:<20} median {statistics.median(values) * 1e3:6.3f} ms   "
              f"p90 {percentile(values, 0.9) * 1e3:6.3f} ms   p99 {percentile(values, 0.99) * 1e3:6.3f} ms")


if __name__ == "__main__":
    main()
