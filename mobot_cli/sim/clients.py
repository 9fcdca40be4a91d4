"""PyBullet clients for Worlds: connected anew, or kept between Worlds that follow one another."""

from __future__ import annotations

import threading

from mobot_cli.sim.bullet import p

_idle: list[int] = []  # connected clients, reset to empty, waiting for a World
_keep = 0
_idle_lock = threading.Lock()  # Worlds may be made and closed in several threads


def keep_clients(count: int) -> None:
    """Keep up to ``count`` PyBullet clients after their Worlds close, for the next Worlds.

    A sweep worker's runs follow one another: connecting a client costs ~15 ms of CPU (and
    more wall time on a busy machine), resetting one to empty a fraction of a millisecond.
    A reset client is a new world: resetSimulation makes a new dynamics world and restarts the
    body ids, and every World sets the same engine parameters on its client (a test compares
    the run folders of every bundled scenario, run one after another in kept clients, with
    fresh runs). 0, the default, disconnects every client when its World closes.
    """
    global _keep
    with _idle_lock:
        _keep = max(0, count)
        extra = _idle[_keep:]
        del _idle[_keep:]
    for cid in extra:
        p.disconnect(physicsClientId=cid)


def connect() -> int:
    """A new PyBullet client (DIRECT, headless), or a kept one reset to empty."""
    with _idle_lock:
        if _idle:
            return _idle.pop()
    return p.connect(p.DIRECT)


def release(cid: int) -> None:
    """Disconnect a World's client, or keep it reset for the next World."""
    with _idle_lock:
        if len(_idle) < _keep and p.isConnected(physicsClientId=cid):
            p.resetSimulation(physicsClientId=cid)
            _idle.append(cid)
            return
    p.disconnect(physicsClientId=cid)
