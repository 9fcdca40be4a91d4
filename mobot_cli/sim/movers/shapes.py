"""Lidar rays against movers' upright shapes, in closed form and in numpy: boxes turned by
their yaw (slabs), cylinders (side and caps) and capsules (side and the two end spheres).

Movers change pose every few steps, so they stay out of the static world's Embree scene
(sim/sensing/raycast.py): a scan is cast at the static world as before and then at the
movers' shapes where they were when it was taken (``Snapshot``), the nearer hit kept.
"""

from __future__ import annotations

import math
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


def see(snap: Snapshot, range_min: float, beams, position, rotation, ranges: np.ndarray) -> None:
    """A lidar scan's ``ranges`` (float32, cast at everything else, before noise) shortened in place
    where its beams (sim/sensing/lidar.py Beams) from the sensor at ``position``, turned by
    ``rotation`` (3 x 3), meet a mover first."""
    dirs = beams.directions @ np.array(rotation).T
    origins = np.array(position) + dirs * range_min
    flat = ranges.reshape(-1)
    # a mover no nearer than a beam's range already is cannot shorten it: its pairs are skipped
    hit = cast(snap, origins, dirs, beams.lengths32.astype(float), flat - range_min, np.array(position, dtype=float))
    if hit is not None:
        np.minimum(flat, (hit + range_min).astype(np.float32), out=flat)


def cast(snap: Snapshot, origins: np.ndarray, dirs: np.ndarray, lengths: np.ndarray,
         seen: np.ndarray | None = None, apex: np.ndarray | None = None) -> np.ndarray | None:
    """Distance along each ray (unit ``dirs``) to the nearest mover within its length (+inf: none);
    None when no mover is within reach of any ray (the usual case, cheaply). ``seen``: how far
    each ray is known to reach already; a mover that can only be further away along a ray may be
    left out for it (+inf there, where it would have been beyond ``seen``). ``apex``: a point every
    ray's line goes through (a lidar's centre, its rays starting ``range_min`` out), when there is one."""
    if not len(snap):
        return None
    centre = origins.mean(axis=0) if apex is None else apex
    longest = float(lengths.max())
    spread = float(np.abs(origins - centre).max()) + longest
    near = np.hypot(snap.x - centre[0], snap.y - centre[1]) <= spread + snap.r
    if not near.any():
        return None
    o, d = np.asarray(origins, dtype=float), np.asarray(dirs, dtype=float)
    round_ = near & (snap.kind != BOX)
    best = _round(o, d, snap, round_.nonzero()[0], seen, apex, longest) if round_.any() else np.full(len(o), np.inf)
    for i in np.flatnonzero(near & (snap.kind == BOX)).tolist():
        np.minimum(best, _box(o, d, snap, i), out=best)
    best[best > lengths] = np.inf
    return best


SEEN_SLACK = 1e-3  # m: a pair is skipped only when its mover is this much beyond what the ray saw
APEX_SLACK = 1e-6  # m added to a mover's radius for the angle it spans from the rays' apex
Z_SLACK = 1e-6  # m around the heights rays pass through, for the parts of a shape they may meet


def _round(o: np.ndarray, d: np.ndarray, snap: Snapshot, index: np.ndarray,
           seen: np.ndarray | None = None, apex: np.ndarray | None = None, reach_along: float = np.inf) -> np.ndarray:
    """Rays (n) against upright cylinders (with caps) and capsules (m of them): the nearest hit of
    each ray. First the (ray, mover) pairs: the rays whose heading lies within the angle a mover
    spans seen from the rays' starts (sorted headings, one search for every mover and every 2 pi
    shift of its bounds), less those whose ray reaches less far than the mover's nearest point
    (``seen``), then the maths on those. Seen from the ``apex`` of the rays' lines, when given, a
    mover spans the angle of its own circle; else that of its circle grown by the rays' spread."""
    out = np.full(len(o), np.inf)
    centre = o.mean(axis=0) if apex is None else apex
    offset = float(np.abs(o[:, :2] - centre[:2]).max()) * 1.5  # at least the rays' starts' distance from it
    spread = offset if apex is None else APEX_SLACK
    heading = np.arctan2(d[:, 1], d[:, 0])
    flat = np.hypot(d[:, 0], d[:, 1]) > 1e-9
    order = heading.argsort(kind="stable")  # (array methods: no Python wrapper a call, this runs a scan)
    ordered = heading[order]
    dx, dy = snap.x[index] - centre[0], snap.y[index] - centre[1]
    dist = np.hypot(dx, dy)
    reach = snap.r[index] + spread
    inside = dist <= reach  # around the rays' starts: every ray may meet it
    half = np.arcsin(np.minimum(reach / np.maximum(dist, 1e-9), 1.0))
    half[inside] = np.pi
    bearing = np.arctan2(dy, dx)
    shift = np.array([[0.0], [2 * np.pi], [-2 * np.pi]])  # each mover's bounds as they are and turned once
    start = ordered.searchsorted((bearing - half + shift).ravel())
    count = ordered.searchsorted((bearing + half + shift).ravel(), side="right") - start
    total = int(count.sum())
    owner = (np.arange(3 * len(index)) % len(index)).repeat(count)
    ray = order[(start - (count.cumsum() - count)).repeat(count) + np.arange(total)]
    if not flat.all():  # rays straight up or down: every mover over their start
        up = np.flatnonzero(~flat)
        near = np.flatnonzero(dist <= reach)
        ray = np.concatenate([ray, np.repeat(up, len(near))])
        owner = np.concatenate([owner, np.tile(near, len(up))])
    if seen is not None and len(ray):  # nearer than the surface ahead
        keep = (dist - snap.r[index] - offset)[owner] <= seen[ray] + SEEN_SLACK
        ray, owner = ray[keep], owner[keep]
    if not len(ray):
        return out
    hits = _round_pairs(o[ray], d[ray], snap, index[owner], reach_along)
    np.minimum.at(out, ray, hits)
    return out


def _round_pairs(o: np.ndarray, d: np.ndarray, snap: Snapshot, i: np.ndarray, reach: float = np.inf) -> np.ndarray:
    """The distance along each ray to its own cylinder or capsule (``i``: one mover a ray). Hits
    further than ``reach`` along a ray may be left out (+inf): the parts of the shapes (side, end
    spheres, caps) that no ray comes to within it are not tested (a 2D lidar below a person's
    waist meets only the bottom sphere)."""
    if not d[:, 2].any():
        return _level_pairs(o, d, snap, i)
    r, z0, z1 = snap.r[i], snap.z0[i], snap.z1[i]
    capsule = snap.kind[i] == PERSON
    people = bool(capsule.all())  # (the usual crowd)
    lo, hi = (z0 + r, z1 - r) if people else (np.where(capsule, z0 + r, z0), np.where(capsule, z1 - r, z1))
    dx, dy, dz = d[:, 0], d[:, 1], d[:, 2]
    px, py, oz = o[:, 0] - snap.x[i], o[:, 1] - snap.y[i], o[:, 2]
    # the heights the rays pass through within ``reach``: a part wholly above or below them is missed
    low, high = -np.inf, np.inf
    if math.isfinite(reach):
        rise = dz * reach
        low = float((oz + np.minimum(rise, 0.0)).min()) - Z_SLACK
        high = float((oz + np.maximum(rise, 0.0)).max()) + Z_SLACK

    def meets(bottom: np.ndarray, top: np.ndarray) -> bool:
        return low <= float(top.max()) and float(bottom.min()) <= high

    r2 = r * r
    b = px * dx + py * dy
    c = px * px + py * py - r2
    out = np.full(len(o), np.inf)
    with np.errstate(invalid="ignore", divide="ignore"):
        if meets(lo, hi):  # the side
            a = dx * dx + dy * dy
            disc = b * b - a * c
            t = (-b - np.sqrt(disc)) / a
            z = oz + t * dz
            out = np.where((disc >= 0.0) & (a > 1e-12) & (t >= 0.0) & (z >= lo) & (z <= hi), t, np.inf)
        for zc in (lo, hi) if people or capsule.any() else ():  # a capsule's end spheres
            if not meets(zc - r, zc + r):
                continue
            pz = oz - zc
            bs = b + pz * dz
            ds = bs * bs - (c + pz * pz)
            ts = -bs - np.sqrt(ds)
            np.minimum(out, np.where((ds >= 0.0) & (ts >= 0.0) & capsule, ts, np.inf), out=out)
        for zc in (z0, z1) if not people else ():  # a cylinder's caps
            if not meets(zc, zc):
                continue
            tc = (zc - oz) / dz
            qx, qy = px + tc * dx, py + tc * dy
            hit = (tc >= 0.0) & (qx * qx + qy * qy <= r2) & ~capsule
            np.minimum(out, np.where(hit, tc, np.inf), out=out)
    return out


def _level_pairs(o: np.ndarray, d: np.ndarray, snap: Snapshot, i: np.ndarray) -> np.ndarray:
    """``_round_pairs`` for level rays (a 2D lidar's): each shape is the circle it cuts at the ray's
    height (a capsule's end spheres narrow it), so one circle test a pair."""
    r, z0, z1, oz = snap.r[i], snap.z0[i], snap.z1[i], o[:, 2]
    capsule = snap.kind[i] == PERSON
    # how far the ray's height is above or below a capsule's straight part
    over = np.where(capsule, np.maximum(np.maximum(z0 + r - oz, oz - (z1 - r)), 0.0), 0.0)
    r2 = r * r - over * over
    r2[(oz < z0) | (oz > z1)] = -1.0
    px, py = o[:, 0] - snap.x[i], o[:, 1] - snap.y[i]
    b = px * d[:, 0] + py * d[:, 1]
    disc = b * b - (px * px + py * py - r2)  # the level directions are unit vectors
    with np.errstate(invalid="ignore"):
        t = -b - np.sqrt(disc)
    return np.where((disc >= 0.0) & (r2 >= 0.0) & (t >= 0.0), t, np.inf)


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
