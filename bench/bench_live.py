#!/usr/bin/env python3
"""How fast does the live world answer? Spawn latency and list/odom requests per second.

Starts a real `mobot serve` process (real time, then --fast), and through the Python client:
- spawn latency, request to reply, for the bundled robot with a warm description cache
  (plus the cold first spawn, with a fresh cache, for reference);
- requests per second for `list` and `odom` from one client, and from 4 clients at once,
  with 5 robots in the world;
- the world's own pace while it is flooded: simulated seconds per wall second;
- the world's pace (steps per wall second) while a hostile spawn loads: a xacro computing
  ${7**(10**7)} and one looping until the load limit stops it, against the pace at rest.

    python3 bench/bench_live.py [--spawns 20] [--requests 2000] [--hostile-only]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
import threading
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

import zmq  # noqa: E402
from common import Server  # noqa: E402  (bench/common.py)

from mobot_cli.live.client import Client  # noqa: E402

HOSTILE = {  # what an attacker sent: seconds of big-int arithmetic; a loop only the load limit ends
    "${7**(10**7)}": "7**(10**7)",
    "10-second loop": "python.sum(python.range(10**12))",
}

TUTORIAL = [(0.0, 0.0), (1.0, 1.0), (2.0, 0.0), (1.0, 2.0), (0.0, 2.0)]


def spawn_latencies(endpoint: str, count: int) -> list[float]:
    """Seconds from request to reply for ``count`` spawns on a 2 m grid."""
    out = []
    with Client(endpoint, timeout=120) as client:
        for i in range(count):
            started = time.perf_counter()
            client.spawn(f"s{i}", description="mobot", pose={"x": 10.0 + 2.0 * (i % 10), "y": 2.0 * (i // 10)})
            out.append(time.perf_counter() - started)
    return out


def rate(endpoint: str, op: str, total: int, clients: int, **fields) -> float:
    """Requests per second answered for ``total`` requests spread over ``clients`` threads."""
    def work(n: int) -> None:
        with Client(endpoint, timeout=30) as client:
            for _ in range(n):
                client.request(op, **fields)

    threads = [threading.Thread(target=work, args=(total // clients,)) for _ in range(clients)]
    started = time.perf_counter()
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    return clients * (total // clients) / (time.perf_counter() - started)


def pace(endpoint: str, seconds: float = 1.0) -> float:
    with Client(endpoint) as client:
        first, t0 = client.ping(), time.perf_counter()
        time.sleep(seconds)
        last, t1 = client.ping(), time.perf_counter()
    return (last["t"] - first["t"]) / (t1 - t0)


def steps_per_second(endpoint: str, seconds: float, hostile: str | None = None) -> tuple[float, float, str]:
    """(steps per wall second, wall seconds, the hostile spawn's result) over ``seconds`` or the load."""
    reply: dict = {}

    def spawn() -> None:
        socket = zmq.Context.instance().socket(zmq.DEALER)
        socket.setsockopt(zmq.LINGER, 0)
        socket.connect(endpoint)
        text = ('<robot name="h" xmlns:xacro="http://www.ros.org/wiki/xacro">'
                f'<link name="${{{hostile}}}"/></robot>')
        socket.send_multipart([b"", json.dumps({"op": "spawn", "name": "hostile", "urdf": text}).encode()])
        if socket.poll(120_000):
            reply.update(json.loads(socket.recv_multipart()[-1]))
        socket.close()

    loader = threading.Thread(target=spawn)
    with Client(endpoint) as client:
        first, started = client.ping()["step"], time.perf_counter()
        if hostile:
            loader.start()
        while (loader.is_alive() if hostile else False) or time.perf_counter() - started < seconds:
            time.sleep(0.05)
        last, wall = client.ping()["step"], time.perf_counter() - started
    if hostile:
        loader.join()
    return (last - first) / wall, wall, reply.get("result", "")


def hostile_pace(mode: list[str], cache: Path, rounds: int) -> None:
    """The world's pace at rest and while each hostile spawn loads, interleaved over ``rounds``."""
    server = Server(*mode, cache=cache)
    try:
        rest: list[float] = []
        loaded: dict[str, list[float]] = {name: [] for name in HOSTILE}
        notes: dict[str, str] = {}
        for _ in range(rounds):
            for name, expression in HOSTILE.items():
                rest.append(steps_per_second(server.endpoint, 4.0)[0])
                pace, wall, result = steps_per_second(server.endpoint, 4.0, expression)
                loaded[name].append(pace)
                notes[name] = f"{result} after {wall:.1f} s"
        base = statistics.median(rest)
        print(f"\n{mode[0]}: world pace while a hostile spawn loads ({rounds} rounds, medians)")
        print(f"  at rest: {base:,.0f} steps/s")
        for name, values in loaded.items():
            pace = statistics.median(values)
            print(f"  {name}: {pace:,.0f} steps/s ({100 * (pace - base) / base:+.1f} %), spawn {notes[name]}")
    finally:
        server.stop()


def ms(values: list[float]) -> str:
    values = sorted(values)
    p90 = values[min(len(values) - 1, int(0.9 * len(values)))]
    return f"median {1000 * statistics.median(values):.1f} ms, p90 {1000 * p90:.1f} ms, max {1000 * values[-1]:.1f} ms"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--spawns", type=int, default=20)
    parser.add_argument("--requests", type=int, default=2000)
    parser.add_argument("--rounds", type=int, default=3, help="hostile-spawn rounds per mode (0: none)")
    parser.add_argument("--hostile-only", action="store_true", help="only the hostile-spawn pace")
    args = parser.parse_args()
    cache = Path(tempfile.mkdtemp(prefix="mobot-bench-cache-"))
    print(f"python {sys.version.split()[0]}, {os.cpu_count()} cores")
    for mode in (["--realtime"], ["--fast"]) if args.rounds > 0 else ():
        hostile_pace(mode, cache, args.rounds)
    if args.hostile_only:
        return
    for mode in (["--realtime"], ["--fast"]):
        server = Server(*mode, cache=cache)
        try:
            started = time.perf_counter()
            with Client(server.endpoint, timeout=120) as client:
                for i, (x, y) in enumerate(TUTORIAL):
                    client.spawn(f"tb_{i}", description="mobot", pose={"x": x, "y": y})
            first = time.perf_counter() - started
            label = "cold cache" if mode == ["--realtime"] else "warm cache"
            print(f"\n{mode[0]}: 5 tutorial robots spawned in {first:.2f} s ({label})")
            print(f"  spawn latency, warm, {args.spawns} robots: {ms(spawn_latencies(server.endpoint, args.spawns))}")
            for op, fields in (("list", {}), ("odom", {"name": "tb_0"})):
                for clients in (1, 4):
                    per_s = rate(server.endpoint, op, args.requests, clients, **fields)
                    robots = 5 + args.spawns
                    print(f"  {op:4s} ({robots} robots), {clients} client(s): {per_s:,.0f} requests/s")
            flood = threading.Thread(target=rate, args=(server.endpoint, "list", args.requests * 2, 4))
            flood.start()
            print(f"  world pace while 4 clients flood it with list: {pace(server.endpoint):.2f}x real time")
            flood.join()
            print(f"  world pace at rest: {pace(server.endpoint):.2f}x real time")
        finally:
            server.stop()


if __name__ == "__main__":
    main()
