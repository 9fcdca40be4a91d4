"""Which robots might touch this step (robot_pairs), found without testing all pairs (close_pairs).

The kinematic engine asks each step which robots might touch (world._robot_pairs). Testing all
N^2 pairs costs 1,000 robots 18 ms a step; a sweep along x (sort, then each robot's window of
``limit`` on either side) finds the same pairs from a few candidates each.
"""

from __future__ import annotations

import numpy as np

from mobot_cli.sim.contacts import CONTACT_SLOP

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


def robot_pairs(everyone: list, reach: np.ndarray, measured: np.ndarray, moves) -> dict:
    """The robots each moving robot might touch this step, in a few numpy passes:
    not those whose circles (reach) stay apart by more than both their steps, nor those
    whose distance, last measured, is more than both have travelled since (and this step).
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
        return {}
    dx, dy = x[i] - x[j], y[i] - y[j]
    travel = np.fromiter([m.travel for m in everyone], float, n)
    margin = bound[i] + bound[j] + CONTACT_SLOP
    gap = np.hypot(dx, dy) - reach[i] - reach[j]
    left = measured[i, j] - travel[i] - travel[j]
    keep = (gap <= margin) & (left <= margin)
    out: dict = {}
    for a, b in zip(i[keep].tolist(), j[keep].tolist()):
        out.setdefault(everyone[a], []).append(everyone[b])
    return out
