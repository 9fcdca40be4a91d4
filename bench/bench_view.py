#!/usr/bin/env python3
"""What does watching cost? `mobot run --view` against a headless run, with a page connected.

Runs the same N-robot scenario (fast, not real time) through ``execute``: without a view, then
with the live view at 20 Hz while a client is connected to the page. The client is a separate
process speaking viser's websocket protocol (it reads and counts every message, as a browser
would, but draws nothing, so its own CPU does not blur the figure on a small machine). Printed:
the wall-time change (best of N, alternating, since other load on a shared machine only slows
runs down), the process's CPU change, the CPU share of the view's own threads, and how many
frames a second the view managed to draw. Then the same for 25 robots.

    python3 bench/bench_view.py [--robots 10] [--seconds 20] [--repeat 5] [--many 25]
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

from bench_run import scenario_text  # noqa: E402

from mobot_cli.run import execute  # noqa: E402
from mobot_cli.scenario.prepare import prepare  # noqa: E402

CLIENT = r'''
import sys, time, msgspec, viser, websockets.sync.client as ws
url, seconds = sys.argv[1], float(sys.argv[2])
c = ws.connect(url, subprotocols=[f"viser-v{viser.__version__}"], max_size=None)
c.send(msgspec.msgpack.encode({"type": "ViewerCameraMessage", "wxyz": [1, 0, 0, 0], "position": [0, -8, 6],
       "fov": 1.3, "near": 0.01, "far": 1000.0, "image_height": 700, "image_width": 1000,
       "look_at": [0, 0, 0], "up_direction": [0, 0, 1]}))
count = size = 0
end = time.monotonic() + seconds
while time.monotonic() < end:
    try:
        m = c.recv(timeout=0.5)
    except TimeoutError:
        continue
    except Exception:
        break
    count += 1
    size += len(m)
print(count, size, flush=True)
'''


def run_once(plan, yaml: str, out: Path, view_rate: float | None, client_seconds: float) -> tuple[float, dict]:
    """Wall seconds of one run; with view_rate, a page at that rate and a client connected."""
    stats: dict = {}
    server = live = client = None
    if view_rate is not None:
        from mobot_cli.view.live import LiveView
        from mobot_cli.view.page import close_page, open_page

        server = open_page(0)
        live = LiveView(server, plan, rate_hz=view_rate)
        client = subprocess.Popen([sys.executable, "-c", CLIENT, f"ws://127.0.0.1:{server.get_port()}",
                                   str(client_seconds)], stdout=subprocess.PIPE, text=True)
        deadline = time.monotonic() + 20
        while not server.get_clients() and time.monotonic() < deadline:
            time.sleep(0.05)
        time.sleep(1.0)  # the scene's backlog reaches the client before the clock starts
    started, cpu = time.perf_counter(), time.process_time()
    frames0 = live.frames if live else 0
    threads = _thread_cpu(exclude_main=True)
    execute(plan, yaml, out, watch=live.watch if live else None)
    wall = time.perf_counter() - started
    stats["cpu"] = time.process_time() - cpu  # every thread of this process: the view's too
    # CPU of the threads besides the simulation's (the view's and viser's), as a share of the run.
    stats["side"] = (_thread_cpu(exclude_main=True) - threads) / wall
    if live is not None:
        stats["frames_per_s"] = (live.frames - frames0) / wall
        live.close()
        client.terminate()
        client.wait()
        close_page(server)
    return wall, stats


def _thread_cpu(exclude_main: bool) -> float:
    """CPU seconds of this process's threads so far (Linux /proc), the main thread left out."""
    total, tick = 0.0, os.sysconf("SC_CLK_TCK")
    for tid in os.listdir("/proc/self/task"):
        if exclude_main and int(tid) == os.getpid():
            continue
        try:
            fields = open(f"/proc/self/task/{tid}/stat").read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        total += (int(fields[11]) + int(fields[12])) / tick
    return total


def measure(robots: int, seconds: float, repeat: int, rate: float) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "s.yaml"
        path.write_text(scenario_text(robots, seconds))
        prepared = prepare(path)
        run_once(prepared.plan, prepared.resolved_yaml, Path(tmp) / "warm", None, 0)  # caches, imports
        base, viewed = [], []  # (wall, stats) alternated, so that load from elsewhere hits both alike
        for i in range(repeat):
            base.append(run_once(prepared.plan, prepared.resolved_yaml, Path(tmp) / f"b{i}", None, 0))
            viewed.append(run_once(prepared.plan, prepared.resolved_yaml, Path(tmp) / f"v{i}", rate, 3600))
        # The fastest of N runs is the one least disturbed by other processes on a shared machine.
        b, v = min(w for w, _ in base), min(w for w, _ in viewed)
        bc, vc = (statistics.median(s["cpu"] for _, s in runs) for runs in (base, viewed))
        frames = statistics.median(s["frames_per_s"] for _, s in viewed)
        side = statistics.median(s["side"] for _, s in viewed) - statistics.median(s["side"] for _, s in base)
        print(f"{robots} robots, {seconds:g} s simulated (fast), best of {repeat}: headless {b:.2f} s, with the "
              f"view at {rate:g} Hz and a client {v:.2f} s: {100 * (v / b - 1):+.1f}% wall; CPU {bc:.2f} s vs "
              f"{vc:.2f} s: {100 * (vc / bc - 1):+.1f}%; the view's threads used {100 * side:.1f}% of a core; it drew "
              f"{frames:.1f} frames/s")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", type=int, default=10)
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--rate", type=float, default=20.0)
    parser.add_argument("--many", type=int, default=25)
    args = parser.parse_args()
    measure(args.robots, args.seconds, args.repeat, args.rate)
    measure(args.many, args.seconds, max(1, args.repeat // 2), args.rate)


if __name__ == "__main__":
    main()
