"""Polygons on a square grid: which cells a shape covers, judged at each cell's centre.

Coverage planning (free space for lanes) and the coverage expectation (the footprint's swept
area) share these. A cell counts as
covered when its centre lies inside the polygon (even-odd rule), so a shape's cell count
times the cell area converges on its true area as the cells shrink; segments (walls seen
edge-on in a floor plan) mark every cell they pass through.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mobot_cli.common.polygon import Point


@dataclass(frozen=True)
class Grid:
    """``nx`` by ``ny`` square cells of side ``cell`` from (x0, y0); arrays are indexed [iy, ix]."""

    x0: float
    y0: float
    cell: float
    nx: int
    ny: int

    @classmethod
    def covering(cls, xmin: float, xmax: float, ymin: float, ymax: float, cell: float) -> "Grid":
        """The grid of whole cells covering a box, anchored on multiples of ``cell`` (so that
        two grids of one cell size share their cell edges)."""
        x0, y0 = math.floor(xmin / cell) * cell, math.floor(ymin / cell) * cell
        nx = max(1, math.ceil((xmax - x0) / cell - 1e-9))
        ny = max(1, math.ceil((ymax - y0) / cell - 1e-9))
        return cls(x0, y0, cell, nx, ny)

    def empty(self) -> np.ndarray:
        """An all-False mask of this grid."""
        return np.zeros((self.ny, self.nx), dtype=bool)

    def centre(self, ix: int, iy: int) -> Point:
        """The centre of cell (ix, iy)."""
        return self.x0 + (ix + 0.5) * self.cell, self.y0 + (iy + 0.5) * self.cell

    def cell_of(self, x: float, y: float) -> tuple[int, int] | None:
        """The (ix, iy) of the cell holding (x, y), or None outside the grid."""
        ix, iy = math.floor((x - self.x0) / self.cell), math.floor((y - self.y0) / self.cell)
        return (ix, iy) if 0 <= ix < self.nx and 0 <= iy < self.ny else None

    def span(self, low: float, high: float, origin: float, n: int) -> tuple[int, int]:
        """Indices whose centres may lie in [low, high], clipped to the grid."""
        first = max(0, math.floor((low - origin) / self.cell - 0.5))
        last = min(n, math.ceil((high - origin) / self.cell + 0.5))
        return first, last


def fill_polygon(mask: np.ndarray, grid: Grid, polygon) -> None:
    """Set the cells of ``mask`` whose centres lie inside ``polygon`` (even-odd; any winding)."""
    pts = np.asarray(polygon, dtype=float)
    if len(pts) < 3:
        return
    x0, x1 = grid.span(pts[:, 0].min(), pts[:, 0].max(), grid.x0, grid.nx)
    y0, y1 = grid.span(pts[:, 1].min(), pts[:, 1].max(), grid.y0, grid.ny)
    if x0 >= x1 or y0 >= y1:
        return
    xs = grid.x0 + (np.arange(x0, x1) + 0.5) * grid.cell
    ys = grid.y0 + (np.arange(y0, y1) + 0.5) * grid.cell
    a, b = pts, np.roll(pts, -1, axis=0)
    crosses = (a[:, None, 1] > ys[None, :]) != (b[:, None, 1] > ys[None, :])  # (edges, rows)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (ys[None, :] - a[:, None, 1]) / (b[:, None, 1] - a[:, None, 1])
        xi = a[:, None, 0] + t * (b[:, None, 0] - a[:, None, 0])
    xi = np.where(crosses, xi, -np.inf)  # an edge that does not cross a row lies left of it all
    inside = (xi[:, :, None] > xs[None, None, :]).sum(axis=0) % 2 == 1  # crossings to the right
    mask[y0:y1, x0:x1] |= inside


def fill_segment(mask: np.ndarray, grid: Grid, a: Point, b: Point) -> None:
    """Set every cell the segment from ``a`` to ``b`` passes through (sampled at a fifth of a cell)."""
    n = max(2, math.ceil(math.hypot(b[0] - a[0], b[1] - a[1]) / (grid.cell / 5)) + 1)
    t = np.linspace(0.0, 1.0, n)
    ix = np.floor((a[0] + t * (b[0] - a[0]) - grid.x0) / grid.cell).astype(int)
    iy = np.floor((a[1] + t * (b[1] - a[1]) - grid.y0) / grid.cell).astype(int)
    keep = (ix >= 0) & (ix < grid.nx) & (iy >= 0) & (iy < grid.ny)
    mask[iy[keep], ix[keep]] = True


def fill_shape(mask: np.ndarray, grid: Grid, shape) -> None:
    """A floor-plan shape: a polygon (3 points or more) or a segment (2 points). A polygon
    thinner than a cell may hold no cell's centre: its corners' cells are set too, and for the
    outline of a solid (more than 3 points) the cells along its longest extent (``_spine``), so a
    glass pane still blocks. A mesh's faces are triangles: floorplan.py draws those seen nearly
    edge-on as segments."""
    if len(shape) >= 3:
        fill_polygon(mask, grid, shape)
        for point in shape:  # a sliver thinner than a cell still blocks the cell it is in
            cell = grid.cell_of(*point)
            if cell is not None:
                mask[cell[1], cell[0]] = True
        spine = _spine(np.asarray(shape, dtype=float), grid.cell) if len(shape) > 3 else None
        if spine is not None:
            fill_segment(mask, grid, *spine)
    elif len(shape) == 2:
        fill_segment(mask, grid, shape[0], shape[1])


def _spine(pts: np.ndarray, cell: float):
    """The two points of a polygon farthest apart when it is longer than ``cell`` and thinner
    (its area over that distance: a strip's width), else None: a smaller one lies in its
    corners' cells."""
    gaps = np.hypot(pts[:, None, 0] - pts[None, :, 0], pts[:, None, 1] - pts[None, :, 1])
    i, j = np.unravel_index(int(gaps.argmax()), gaps.shape)
    x, y = pts[:, 0], pts[:, 1]
    area2 = abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))
    if gaps[i, j] <= cell or area2 >= 2.0 * cell * gaps[i, j]:
        return None
    return tuple(pts[i]), tuple(pts[j])


def dilate(mask: np.ndarray, cells: float) -> np.ndarray:
    """``mask`` grown by a disc of radius ``cells`` (in cells): every cell within that distance
    of a set cell is set."""
    reach = int(math.floor(cells))
    out = mask.copy()
    ny, nx = mask.shape
    for dy in range(-reach, reach + 1):
        for dx in range(-reach, reach + 1):
            if (dx or dy) and dx * dx + dy * dy <= cells * cells:
                src = mask[max(0, -dy):ny - max(0, dy), max(0, -dx):nx - max(0, dx)]
                out[max(0, dy):ny - max(0, -dy), max(0, dx):nx - max(0, -dx)] |= src
    return out


SMALL = 8  # cells: a triangle whose candidate cells span at most this many each way is batched


def fill_shapes(mask: np.ndarray, grid: Grid, shapes) -> None:
    """``fill_shape`` for many shapes at once, cell for cell the same: triangles spanning a few
    cells and segments are rasterised together with numpy, the rest one by one. A furnished
    world's floor plan holds a million triangles; one by one they take minutes."""
    triangles = [shape for shape in shapes if len(shape) == 3]
    segments = [shape for shape in shapes if len(shape) == 2]
    for shape in shapes:
        if len(shape) > 3:
            fill_shape(mask, grid, shape)
    fill_arrays(mask, grid, np.asarray(triangles, dtype=float).reshape(-1, 3, 2),
                np.asarray(segments, dtype=float).reshape(-1, 2, 2))


def fill_arrays(mask: np.ndarray, grid: Grid, triangles: np.ndarray, segments: np.ndarray) -> None:
    """``fill_shapes`` for triangles (n, 3, 2) and segments (m, 2, 2) held as arrays."""
    if len(triangles):
        _fill_triangles(mask, grid, triangles)
    if len(segments):
        _fill_segments(mask, grid, segments)


def _spans(low: np.ndarray, high: np.ndarray, origin: float, cell: float, n: int):
    """Grid.span for arrays."""
    first = np.maximum(0, np.floor((low - origin) / cell - 0.5)).astype(np.int64)
    last = np.minimum(n, np.ceil((high - origin) / cell + 0.5)).astype(np.int64)
    return first, last


def _fill_triangles(mask: np.ndarray, grid: Grid, tri: np.ndarray) -> None:
    """fill_polygon (even-odd at cell centres) and the cells of the corners, for (n, 3, 2) triangles."""
    x0, x1 = _spans(tri[:, :, 0].min(axis=1), tri[:, :, 0].max(axis=1), grid.x0, grid.cell, grid.nx)
    y0, y1 = _spans(tri[:, :, 1].min(axis=1), tri[:, :, 1].max(axis=1), grid.y0, grid.cell, grid.ny)
    w, h = x1 - x0, y1 - y0
    some = (w > 0) & (h > 0)
    small = some & (w <= SMALL) & (h <= SMALL)
    for i in np.nonzero(some & ~small)[0]:
        fill_polygon(mask, grid, tri[i])
    idx = np.nonzero(small)[0]
    offsets = np.arange(SMALL)
    for start in range(0, len(idx), 20_000):
        part = idx[start:start + 20_000]
        t, ix0, iy0 = tri[part], x0[part], y0[part]
        cols, rows = ix0[:, None] + offsets, iy0[:, None] + offsets  # (n, SMALL)
        xs = grid.x0 + (cols + 0.5) * grid.cell
        ys = grid.y0 + (rows + 0.5) * grid.cell
        a, b = t, np.roll(t, -1, axis=1)  # (n, 3 edges, xy)
        ay, by = a[:, :, 1, None], b[:, :, 1, None]
        yy = ys[:, None, :]
        crosses = (ay > yy) != (by > yy)  # (n, edges, rows)
        with np.errstate(divide="ignore", invalid="ignore"):
            xi = a[:, :, 0, None] + (yy - ay) / (by - ay) * (b[:, :, 0, None] - a[:, :, 0, None])
        xi = np.where(crosses, xi, -np.inf)
        inside = (xi[:, :, :, None] > xs[:, None, None, :]).sum(axis=1) % 2 == 1  # (n, rows, cols)
        valid = (offsets[None, :, None] < h[part, None, None]) & (offsets[None, None, :] < w[part, None, None])
        n, r, c = np.nonzero(inside & valid)
        mask[rows[n, r], cols[n, c]] = True
    _fill_points(mask, grid, tri.reshape(-1, 2))


def _fill_points(mask: np.ndarray, grid: Grid, points: np.ndarray) -> None:
    """The cells holding the points (Grid.cell_of), where inside the grid."""
    ix = np.floor((points[:, 0] - grid.x0) / grid.cell)
    iy = np.floor((points[:, 1] - grid.y0) / grid.cell)
    keep = (ix >= 0) & (ix < grid.nx) & (iy >= 0) & (iy < grid.ny)
    mask[iy[keep].astype(np.int64), ix[keep].astype(np.int64)] = True


def _fill_segments(mask: np.ndarray, grid: Grid, seg: np.ndarray) -> None:
    """fill_segment for (n, 2 ends, 2) segments: the same samples (np.linspace's arithmetic)."""
    a, b = seg[:, 0], seg[:, 1]
    d = b - a
    counts = np.maximum(2, np.ceil(np.hypot(d[:, 0], d[:, 1]) / (grid.cell / 5)).astype(np.int64) + 1)
    owner = np.repeat(np.arange(len(seg)), counts)
    first = np.cumsum(counts) - counts
    i = np.arange(len(owner)) - first[owner]
    t = i * (1.0 / (counts - 1))[owner] + 0.0
    t[first + counts - 1] = 1.0
    ix = np.floor((a[owner, 0] + t * d[owner, 0] - grid.x0) / grid.cell).astype(int)
    iy = np.floor((a[owner, 1] + t * d[owner, 1] - grid.y0) / grid.cell).astype(int)
    keep = (ix >= 0) & (ix < grid.nx) & (iy >= 0) & (iy < grid.ny)
    mask[iy[keep], ix[keep]] = True
