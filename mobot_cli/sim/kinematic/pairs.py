"""Which robots might touch this step (robot_pairs), found without testing all pairs (close_pairs).

The kinematic engine asks each step which robots might touch (world._robot_pairs). Testing all
N^2 pairs costs 1,000 robots 18 ms a step; a sweep along x (sort, then each robot's window of
``limit`` on either side) finds the same pairs from a few candidates each.
"""

from __future__ import annotations

import numpy as np

from mobot_cli.sim.contacts import CONTACT_SLOP
from mobot_cli.sim.kinematic.footprint import placed_gap

# The window is widened by this (relative) before the exact test, so that no rounding of
# x - limit can leave out a pair the exact test keeps.
WIDEN = 1e-9


def close_pairs(x: np.ndarray, y: np.ndarray, limit: float, rows: np.ndarray | None = None):
    """Indices (i, j), i != j, with |x[i] - x[j]| <= limit and |y[i] - y[j]| <= limit, sorted by
    i then j (np.nonzero's order over the all-pairs matrix); only rows i where ``rows`` is True."""
    by_x = np.argsort(x, kind="stable")
    xs = x[by_x]
    wide = limit + abs(limit) * WIDEN + WIDEN
    start = np.searchsorted(xs, xs - wide, side="left")
    stop = np.searchsorted(xs, xs + wide, side="right")
    order = by_x
    if rows is not None:  # only the windows of the rows asked for
        keep = rows[by_x]
        order, start, stop = by_x[keep], start[keep], stop[keep]
    counts = stop - start
    total = int(counts.sum())
    if not total:
        return np.zeros(0, np.intp), np.zeros(0, np.intp)
    i = np.repeat(order, counts)
    # positions start..stop-1 of each window, all windows end to end
    offsets = np.repeat(start - (np.cumsum(counts) - counts), counts)
    j = by_x[np.arange(total) + offsets]
    ok = (i != j) & (np.abs(x[i] - x[j]) <= limit) & (np.abs(y[i] - y[j]) <= limit)
    i, j = i[ok], j[ok]
    first = np.lexsort((j, i))
    return i[first], j[first]


def robot_pairs(everyone: list, reach: np.ndarray, measured: np.ndarray, moves,
                shapes: np.ndarray | None = None) -> dict:
    """The robots each moving robot might touch this step, in a few numpy passes:
    not those whose circles (reach) stay apart by more than both their steps, nor those
    whose distance, last measured, is more than both have travelled since (and this step),
    nor those whose footprints do (``shapes``: each robot's footprint rectangle as centre x, y
    and half sizes in its root frame, NaN for none, see footprint.py), unless the moving robot
    touched something at its last query (what it touched must be asked again).
    ``everyone``: the robots (Movers) in order; ``reach``: their circles' radii; ``measured``:
    pair distances when last measured plus both travels then (world._measured)."""
    n = len(everyone)
    x = np.fromiter([m.x for m in everyone], float, n)
    y = np.fromiter([m.y for m in everyone], float, n)
    bound = np.zeros(n)
    rows = [mover.index for mover, _ in moves]
    bound[rows] = [mover.bound for mover, _ in moves]
    # First the pairs no farther apart along x and y than any pair's circles and steps can
    # reach (most are farther), found by a sweep along x (close_pairs), then the
    # test itself on them alone, in the order and with the numbers an all-pairs pass gives.
    limit = 2.0 * (bound.max() + reach.max()) + CONTACT_SLOP + 1e-9
    moving = None
    if len(rows) < n:  # only the moving robots' rows
        moving = np.zeros(n, bool)
        moving[rows] = True
    i, j = close_pairs(x, y, limit, moving)
    if not len(i):
        return _with_touched({}, everyone, moves)
    dx, dy = x[i] - x[j], y[i] - y[j]
    travel = np.fromiter([m.travel for m in everyone], float, n)
    margin = bound[i] + bound[j] + CONTACT_SLOP
    gap = np.hypot(dx, dy) - reach[i] - reach[j]
    left = measured[i, j] - travel[i] - travel[j]
    keep = (gap <= margin) & (left <= margin)
    if shapes is not None:
        keep &= ~(footprint_gaps(everyone, x, y, shapes, i, j) > margin)
    out: dict = {}
    for a, b in zip(i[keep].tolist(), j[keep].tolist()):
        out.setdefault(everyone[a], []).append(everyone[b])
    return _with_touched(out, everyone, moves)


def _with_touched(near: dict, everyone: list, moves) -> dict:
    """``near`` with the robots each moving robot touched at its last query added: what it
    touched is asked again, wherever either went since."""
    by_body = None
    for mover, _ in moves:
        if not mover.touches:
            continue
        if by_body is None:
            by_body = {m.robot.body: m for m in everyone}
        for body in mover.touches:
            other = by_body.get(body)
            if other is not None and other is not mover and other not in near.get(mover, ()):
                near.setdefault(mover, []).append(other)
    return near


def footprint_gaps(everyone: list, x: np.ndarray, y: np.ndarray, shapes: np.ndarray, i: np.ndarray,
                   j: np.ndarray) -> np.ndarray:
    """footprint.gap of each pair (i, j) of robots at (x, y) now, NaN where either has no
    footprint or is not level, or i touched something at its last query."""
    n = len(everyone)
    yaw = np.fromiter([m.yaw for m in everyone], float, n)
    level = np.fromiter([m.level for m in everyone], bool, n)
    free = np.fromiter([not m.touches for m in everyone], bool, n)
    c, s = np.cos(yaw), np.sin(yaw)
    mx, my, hx, hy = shapes.T
    cx, cy = x + c * mx - s * my, y + s * mx + c * my  # the rectangles' centres in the world
    found = placed_gap(cx[i], cy[i], c[i], s[i], hx[i], hy[i], cx[j], cy[j], c[j], s[j], hx[j], hy[j],
                 most=lambda *terms: np.maximum.reduce(terms))
    found[~(level[i] & level[j] & free[i])] = np.nan
    return found


def touched_pairs(everyone: list, by_body: dict) -> set:
    """A contact sample from what each robot (Mover) touched at its last query: (robot,
    ("body", id)) for a static body, (robot, ("robot", name)) both ways for two robots
    (``by_body``: body id -> SimRobot of the robots)."""
    pairs = set()
    for mover in everyone:
        if not mover.touches:
            continue
        robot = mover.robot
        for other in mover.touches:
            hit = by_body.get(other)
            if hit is None:
                pairs.add((robot, ("body", other)))
            elif hit is not robot:
                pairs.add((robot, ("robot", hit.name)))
                pairs.add((hit, ("robot", robot.name)))
    return pairs
