"""Lidar rays against movers' upright shapes, in closed form and in numpy: boxes turned by
their yaw (slabs), cylinders (side and caps) and capsules (side and the two end spheres).

Movers change pose every few steps, so they stay out of the static world's Embree scene
(sim/sensing/raycast.py): a scan is cast at the static world as before and then at the
movers' shapes where they were when it was taken (``Snapshot``), the nearer hit kept.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

BOX, CYLINDER, PERSON = 0, 1, 2
KINDS = {"box": BOX, "cylinder": CYLINDER, "person": PERSON}


@dataclass(frozen=True)
class Snapshot:
    """Movers' shapes at one instant (arrays, one entry a mover)."""

    kind: np.ndarray  # BOX, CYLINDER or PERSON
    x: np.ndarray
    y: np.ndarray
    yaw: np.ndarray
    r: np.ndarray  # radius (box: half of the xy diagonal, for the reach test)
    hx: np.ndarray  # box half sizes (0 for round shapes)
    hy: np.ndarray
    z0: np.ndarray  # bottom
    z1: np.ndarray  # top

    def __len__(self) -> int:
        return len(self.x)


def cast(snap: Snapshot, origins: np.ndarray, dirs: np.ndarray, lengths: np.ndarray) -> np.ndarray | None:
    """Distance along each ray (unit ``dirs``) to the nearest mover within its length (+inf: none);
    None when no mover is within reach of any ray (the usual case, cheaply)."""
    if not len(snap):
        return None
    centre = origins.mean(axis=0)
    spread = float(np.abs(origins - centre).max()) + float(lengths.max())
    near = np.hypot(snap.x - centre[0], snap.y - centre[1]) <= spread + snap.r
    if not near.any():
        return None
    o, d = origins.astype(float), dirs.astype(float)
    best = np.full(len(o), np.inf)
    for i in np.flatnonzero(near):
        kind = snap.kind[i]
        if kind == BOX:
            t = _box(o, d, snap, i)
        else:
            t = _round(o, d, snap, i, capsule=kind == PERSON)
        np.minimum(best, t, out=best)
    best[best > lengths] = np.inf
    return best


def _round(o: np.ndarray, d: np.ndarray, snap: Snapshot, i: int, capsule: bool) -> np.ndarray:
    """Rays against an upright cylinder (with caps) or capsule."""
    r, z0, z1 = float(snap.r[i]), float(snap.z0[i]), float(snap.z1[i])
    px, py = o[:, 0] - snap.x[i], o[:, 1] - snap.y[i]
    a = d[:, 0] ** 2 + d[:, 1] ** 2
    b = px * d[:, 0] + py * d[:, 1]
    c = px * px + py * py - r * r
    disc = b * b - a * c
    out = np.full(len(o), np.inf)
    lo, hi = (z0 + r, z1 - r) if capsule else (z0, z1)
    with np.errstate(invalid="ignore", divide="ignore"):
        t = (-b - np.sqrt(disc)) / a
        z = o[:, 2] + t * d[:, 2]
        side = (disc >= 0.0) & (a > 1e-12) & (t >= 0.0) & (z >= lo) & (z <= hi)
        out[side] = t[side]
        if capsule:
            for zc in (lo, hi):
                np.minimum(out, _sphere(o, d, snap.x[i], snap.y[i], zc, r), out=out)
        else:
            for zc in (z0, z1):
                tc = (zc - o[:, 2]) / d[:, 2]
                qx, qy = px + tc * d[:, 0], py + tc * d[:, 1]
                cap = (tc >= 0.0) & (qx * qx + qy * qy <= r * r)
                out[cap] = np.minimum(out[cap], tc[cap])
    return out


def _sphere(o: np.ndarray, d: np.ndarray, cx: float, cy: float, cz: float, r: float) -> np.ndarray:
    p = o - np.array([cx, cy, cz])
    b = np.einsum("ij,ij->i", p, d)
    c = np.einsum("ij,ij->i", p, p) - r * r
    disc = b * b - c
    t = -b - np.sqrt(np.maximum(disc, 0.0))
    return np.where((disc >= 0.0) & (t >= 0.0), t, np.inf)


def _box(o: np.ndarray, d: np.ndarray, snap: Snapshot, i: int) -> np.ndarray:
    """Rays against a box turned by its yaw: the slab test in the box's frame."""
    c, s = np.cos(snap.yaw[i]), np.sin(snap.yaw[i])
    px, py = o[:, 0] - snap.x[i], o[:, 1] - snap.y[i]
    lo_ = np.array([-snap.hx[i], -snap.hy[i], snap.z0[i]])
    hi_ = np.array([snap.hx[i], snap.hy[i], snap.z1[i]])
    local_o = np.stack([c * px + s * py, -s * px + c * py, o[:, 2]], axis=1)
    local_d = np.stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1], d[:, 2]], axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / local_d
        a, b = (lo_ - local_o) * inv, (hi_ - local_o) * inv
        enter = np.nanmax(np.minimum(a, b), axis=1)
        leave = np.nanmin(np.maximum(a, b), axis=1)
    hit = (enter <= leave) & (enter >= 0.0)
    return np.where(hit, enter, np.inf)
