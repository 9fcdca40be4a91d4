"""PyBullet clients for Worlds: connected anew, or kept between Worlds that follow one another.

A sweep worker's runs follow one another, and each would otherwise connect a new client and build
its static world again (a house of meshes). So a kept client keeps its static world too (a Stage),
with the robots removed, when the next World has the same physics and world plan and the run left
the world as a fresh one would be: robots removed newest first, so that PyBullet hands the same
body ids out again in the same order. A run that removed a body on the way (a deleted robot, a
refused spawn) or faulted (NaN states) is reset to empty instead: resetSimulation makes a new
dynamics world and restarts the body ids. Either way the next run writes the same run folder, byte
for byte, as in a new client (tests/sim/test_clients.py).
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, field
from typing import Any, Iterable, Optional

from mobot_cli.sim.pb import p


@dataclass
class Stage:
    """A client's static world, as a World built it: what the next World with ``key`` reuses."""

    key: Any  # (Physics, WorldPlan)
    statics: dict[int, str]
    solids: set[int]
    ground: Optional[int]
    probes: Any  # placement.Probes: shapes made once per client
    names: dict[int, str] = field(default_factory=dict)  # static body id -> its name in the world
    body: Any = None  # kept_body.KeptBody: a robot's body left in the client for the same spawn
    meshes: set[int] = field(default_factory=set)  # static bodies holding triangle meshes


_idle: list[tuple[int, Optional[Stage]]] = []  # kept clients, each empty or holding a stage
_keep = 0
_idle_lock = threading.Lock()  # Worlds may be made and closed in several threads


def keep_clients(count: int) -> None:
    """Keep up to ``count`` PyBullet clients after their Worlds close, for the next Worlds.

    0, the default, disconnects every client when its World closes.
    """
    global _keep
    with _idle_lock:
        _keep = max(0, count)
        extra = _idle[_keep:]
        del _idle[_keep:]
    for cid, _ in extra:
        p.disconnect(physicsClientId=cid)


def keep_at_least(count: int) -> None:
    """Keep at least ``count`` clients (keep_clients), never fewer than asked before: for a
    Gymnasium env, whose every reset builds the same world again."""
    with _idle_lock:
        more = count > _keep
    if more:
        keep_clients(count)


def connect(key: Any = None, fresh: bool = False) -> tuple[int, Optional[Stage]]:
    """A PyBullet client (DIRECT, headless) and, when a kept one holds the static world for
    ``key``, that stage (else None: an empty client, new or reset). ``fresh``: a new client, never
    a kept one (a world with cameras: TinyRenderer was seen to leave a robot out of the images in a
    client another world had used, in a process that keeps clients)."""
    if fresh:
        return p.connect(p.DIRECT), None
    with _idle_lock:
        same = next((i for i, (_, stage) in enumerate(_idle) if stage is not None and stage.key == key), None)
        if same is not None:
            return _idle.pop(same)
        kept = _idle.pop() if _idle else None
    if kept is None:
        return p.connect(p.DIRECT), None
    cid, stage = kept
    if stage is not None:  # another world's: start from empty
        p.resetSimulation(physicsClientId=cid)
    return cid, None


def adopt(cid: int) -> None:
    """Keep a client connected just now and never used (empty) for the next World, as ``release``
    keeps a World's; disconnect it when no more are kept."""
    with _idle_lock:
        if len(_idle) < _keep:
            _idle.append((cid, None))
            return
    p.disconnect(physicsClientId=cid)


def release(cid: int, stage: Optional[Stage] = None, robots: Iterable[int] = ()) -> None:
    """Disconnect a World's client, or keep it: with its ``stage`` once the ``robots`` (body
    ids) are removed, or reset to empty when there is no stage to keep."""
    with _idle_lock:
        keep = len(_idle) < _keep
    if keep and p.isConnected(physicsClientId=cid):
        if stage is not None:
            for body in sorted(robots, reverse=True):  # newest first: the ids come back in order
                p.removeBody(body, physicsClientId=cid)
            if p.getNumBodies(physicsClientId=cid) != len(stage.statics) + (stage.body is not None):
                stage = None
        if stage is None:
            p.resetSimulation(physicsClientId=cid)
        with _idle_lock:
            if len(_idle) < _keep:
                _idle.append((cid, stage))
                return
    p.disconnect(physicsClientId=cid)
