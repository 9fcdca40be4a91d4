#!/usr/bin/env python3
"""Does a hostile client slow the live world? Its pace with and without one (issue 26 item 5).

Starts a real `mobot serve` (real time by default: the pace is simulated seconds per wall
second; with --fast it is steps per wall second) with the default bounds, and measures its
pace over windows of --window seconds, at rest and while one hostile client:

- meshes:    spawns 5 robots whose collision mesh has just under --max-faces faces, one after
             the other (the robots are deleted after the window);
- robots:    sends spawn requests as fast as it can: the world fills up to --max-robots, then
             every further spawn is refused (the robots are deleted after the window);
- malformed: floods the endpoint with garbage: bytes that are not JSON, unknown ops, deep
             nesting, oversized and non-finite fields.

Windows are interleaved (rest, attack, rest, attack, ...) over --rounds; medians are printed.

    python3 bench/bench_hostile.py [--fast] [--window 8] [--rounds 3] [--only meshes]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import threading
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

import numpy as np  # noqa: E402
import zmq  # noqa: E402
from common import Server  # noqa: E402  (bench/common.py)

from mobot_cli.live.client import Client  # noqa: E402
from mobot_cli.live.loader import Limits  # noqa: E402

INERTIAL = ('<inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" '
            'iyz="0"/></inertial>')


def robot(shape: str) -> str:
    return (f'<?xml version="1.0"?><robot name="r"><link name="base">{INERTIAL}<collision><geometry>'
            f'{shape}</geometry></collision></link></robot>')


def sheet(path: Path, faces: int) -> Path:
    """An OBJ of ``faces`` triangles: a bumpy 0.4 m square."""
    n = int((faces / 2) ** 0.5) + 2
    x, y = np.meshgrid(np.linspace(-0.2, 0.2, n), np.linspace(-0.2, 0.2, n), indexing="ij")
    z = 0.01 * np.sin(40 * x) * np.cos(40 * y)
    idx = np.arange(n * n).reshape(n, n) + 1
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    tris = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])[:faces]
    with open(path, "w") as obj:
        np.savetxt(obj, np.stack([x.ravel(), y.ravel(), z.ravel()], 1), fmt="v %.5f %.5f %.5f")
        np.savetxt(obj, tris, fmt="f %d %d %d")
    return path


def pace(endpoint: str, seconds: float, key: str, attack=None) -> float:
    """Simulated seconds (key 't') or steps ('step') per wall second over ``seconds``, while ``attack(stop)`` runs."""
    stop = threading.Event()
    thread = threading.Thread(target=attack, args=(stop,)) if attack else None
    with Client(endpoint, timeout=60) as client:
        first, started = client.ping()[key], time.perf_counter()
        if thread:
            thread.start()
        time.sleep(seconds)
        last, wall = client.ping()[key], time.perf_counter() - started
    stop.set()
    if thread:
        thread.join()
    return (last - first) / wall


def clear(endpoint: str, keep: set[str]) -> None:
    with Client(endpoint, timeout=120) as client:
        for entry in client.list():
            if entry["name"] not in keep:
                client.delete(entry["name"])


def meshes(endpoint: str, folder: Path, faces: int):
    mesh = sheet(folder / "heavy.obj", faces)
    text = robot(f'<mesh filename="{mesh}"/>')

    def attack(stop: threading.Event) -> None:
        with Client(endpoint, timeout=300) as client:
            for i in range(5):
                if stop.is_set():
                    return
                reply = client.call("spawn", name=f"heavy{i}", urdf=text, base_dir=str(folder),
                                    pose={"x": 3.0 * i, "y": 20.0})
                attack.results.append(reply["result"])
    attack.results = []
    return attack


def robots(endpoint: str):
    text = robot('<box size="0.2 0.2 0.2"/>')

    def attack(stop: threading.Event) -> None:
        with Client(endpoint, timeout=300) as client:
            i = 0
            while not stop.is_set():
                reply = client.call("spawn", name=f"many{i}", urdf=text,
                                    pose={"x": 1.0 * (i % 20), "y": -10.0 - 1.0 * (i // 20)})
                attack.results.append(reply["result"])
                i += 1
    attack.results = []
    return attack


GARBAGE = [b"\xff\xfe not json", b"{}", b'{"op": "fly"}', b"[" * 10_000, b'{"op": "cmd", "name": "x", '
           b'"linear": 1e999}', b'{"op": "spawn", "name": "' + b"a" * 100_000 + b'"}', b'{"op": 7}',
           b'{"op": "step", "steps": -1}', b'{"op": "odom", "name": {"deep": [[[[[]]]]]}}']


def malformed(endpoint: str):
    def attack(stop: threading.Event) -> None:
        socket = zmq.Context.instance().socket(zmq.DEALER)
        socket.setsockopt(zmq.LINGER, 0)
        socket.connect(endpoint)
        sent = 0
        while not stop.is_set():
            socket.send_multipart([b"", GARBAGE[sent % len(GARBAGE)]])
            sent += 1
            while socket.poll(0):
                socket.recv_multipart()
                attack.results.append("reply")
            if sent % 64 == 0:  # keep the pipe full without queueing forever
                socket.poll(10)
        socket.close()
    attack.results = []
    return attack


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fast", action="store_true", help="measure steps per second of a --fast world")
    parser.add_argument("--window", type=float, default=8.0)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--only", choices=("meshes", "robots", "malformed"), action="append")
    args = parser.parse_args()
    kinds = args.only or ["meshes", "robots", "malformed"]
    key = "step" if args.fast else "t"
    folder = Path(tempfile.mkdtemp(prefix="mobot-hostile-"))
    server = Server(*(["--fast"] if args.fast else ["--realtime"]), cache=folder / "cache")
    limits = Limits()
    try:
        rest: list[float] = []
        under: dict[str, list[float]] = {kind: [] for kind in kinds}
        outcomes: dict[str, dict[str, int]] = {kind: {} for kind in kinds}
        for _ in range(args.rounds):
            for kind in kinds:
                rest.append(pace(server.endpoint, args.window, key))
                attack = {"meshes": lambda: meshes(server.endpoint, folder, int(0.95 * limits.faces)),
                          "robots": lambda: robots(server.endpoint),
                          "malformed": lambda: malformed(server.endpoint)}[kind]()
                under[kind].append(pace(server.endpoint, args.window, key, attack))
                for result in attack.results:
                    outcomes[kind][result] = outcomes[kind].get(result, 0) + 1
                clear(server.endpoint, keep=set())
        base = statistics.median(rest)
        unit = "steps/s" if args.fast else "x real time"
        print(f"\n{'--fast' if args.fast else '--realtime'} world, windows of {args.window:g} s, "
              f"{args.rounds} rounds (medians); bounds: {limits.faces} faces, {limits.robots} robots")
        print(f"  at rest: {base:,.3f} {unit} (windows {', '.join(f'{v:.3f}' for v in rest)})")
        for kind, values in under.items():
            value = statistics.median(values)
            seen = ", ".join(f"{n} {r}" for r, n in sorted(outcomes[kind].items()))
            print(f"  {kind}: {value:,.3f} {unit} ({100 * (value - base) / base:+.1f} %); replies: {seen}")
    finally:
        server.stop()


if __name__ == "__main__":
    main()
