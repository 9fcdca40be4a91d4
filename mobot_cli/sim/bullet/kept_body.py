"""A robot body kept in a PyBullet client between Worlds, for the same robot spawned again.

A Gymnasium env spawns the same robot at the same pose in every reset; loading its URDF is
most of what the kept static world (sim/bullet/clients.py) leaves of a reset. With
``keeping_robot_bodies()`` (the env's ``reset`` holds it: no other World in the process keeps or
takes a body, and one closed outside it is removed as usual), the first robot a World spawns at step 0 is
saved as PyBullet loaded it (``saveState``, in memory), and when its World closes clean the body
stays in the kept client with that saved state. The next World's first spawn of the same URDF
text at the same pose takes it back: ``restoreState`` puts every body where it was just after the
load (positions, velocities, contact points), and the spawn goes on as for a loaded body (joint
motors freed, friction and damping set again: absolute values, so the same as the first time).
Any other first spawn removes the kept body first, so the new one gets the id a new client gives.
Episodes are byte for byte those of a build from nothing (tests/gym/test_resets.py). A sweep's
workers keep bodies too, from the second run in a row with the same first spawn on (the records of
each run are those of a run in a new client: tests/sweep/test_warm_workers.py).
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass
from typing import Any, Optional

from mobot_cli.sim.bullet import settled as settled_state
from mobot_cli.sim.pb import p

_keep = False
_repeated = False  # keep a body only for a first spawn that came twice in a row (see keeping_robot_bodies)
_last: Any = None  # the key of the last first spawn loaded
PARK_Z = 1.0e4  # m: above any world mobot builds


@dataclass(frozen=True)
class KeptBody:
    """A robot's body left in a client, and the world's state saved just after its load."""

    key: Any  # (URDF text, xyz, quat) of the spawn that loaded it
    body: int
    state: int  # a p.saveState id
    settled: Any = None  # settled.Settled: the end of its first settle, put back by the next ones


@contextlib.contextmanager
def keeping_robot_bodies(on: bool = True, repeated: bool = False):
    """Within the block, keep the first robot's body of each World in its kept client; with
    ``repeated``, only a body whose first spawn is the same as the one loaded before it (a sweep
    worker's runs: saving a body's state costs about a millisecond, which runs that each spawn
    another robot or pose would pay for nothing)."""
    global _keep, _repeated, _last
    before, _keep, _repeated, _last = (_keep, _repeated, _last), bool(on), bool(repeated), None
    try:
        yield
    finally:
        _keep, _repeated, _last = before


def body_key(urdf: str, xyz, quat) -> tuple:
    return urdf, tuple(xyz), tuple(quat)


def take(cid: int, kept: Optional[KeptBody], key: tuple) -> Optional[int]:
    """The kept body, put back as just loaded, when it was loaded for ``key``; else None (the
    kept body, if any, removed: the next load gets its id)."""
    if kept is None:
        return None
    if kept.key == key:
        p.restoreState(stateId=kept.state, physicsClientId=cid)
        return kept.body
    forget(cid, kept)
    return None


def forget(cid: int, kept: KeptBody) -> None:
    """Take the kept body out of the world and drop its saved states."""
    p.removeBody(kept.body, physicsClientId=cid)
    p.removeState(kept.state, physicsClientId=cid)
    settled_state.drop(cid, kept.settled)


def leave(cid: int, stage, kept: Optional[KeptBody], waits: bool, bodies: list[int]) -> tuple[Any, list[int]]:
    """A closing World's stage (clients.Stage or None), with the kept body on it when the body is
    still in the world and bodies are being kept, and the robot bodies release() removes: every
    other one (all of them, the kept one too, when it is not kept)."""
    if kept is not None and (stage is None or not _keep):
        p.removeState(kept.state, physicsClientId=cid)
        settled_state.drop(cid, kept.settled)
    if stage is None or kept is None or not _keep or not (waits or kept.body in bodies):
        return stage, bodies
    if not waits:
        park(stage.probes.cid, kept.body)
    stage.body = kept
    return stage, [body for body in bodies if body != kept.body]


def park(cid: int, body: int) -> None:
    """Put the kept body far above the world and let the collision pass drop its contacts: the
    contact points of the episode before (their impulses warm-start the solver) must not meet the
    restored body where it stands again."""
    p.resetBasePositionAndOrientation(body, (0.0, 0.0, PARK_Z), (0.0, 0.0, 0.0, 1.0), physicsClientId=cid)
    p.performCollisionDetection(physicsClientId=cid)


def save(cid: int, key: tuple, body: int) -> Optional[KeptBody]:
    """The body just loaded, saved to be kept (None outside keeping_robot_bodies, or when only a
    repeated first spawn is kept and this one is not)."""
    global _last
    if not _keep:
        return None
    repeat, _last = key == _last, key
    return KeptBody(key, body, p.saveState(physicsClientId=cid)) if repeat or not _repeated else None
