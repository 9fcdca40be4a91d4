"""trajectory.png: robots' paths over a floor plan, drawn with Pillow.

Pillow, not matplotlib: importing matplotlib alone takes longer than a whole short run, while
Pillow imports and draws a plot in a small part of one. Lines are
drawn at twice the size and scaled down, which smooths them. Metres on both axes, one scale
for x and y (equal aspect), a grid at the tick marks, the legend in a panel on the right.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from pathlib import Path

from PIL import Image, ImageDraw, ImageFont

from mobot_cli.assets.world.floorplan import MeshShadow, Part
from mobot_cli.common.files import write_bytes_atomic
from mobot_cli.record.png import encode_rgb

Point = tuple[float, float]
WIDTH, HEIGHT = 1200, 900  # pixels of the saved image
SS = 2  # drawn at SS times the size, then reduced: smooth lines without an antialiasing API
MARGIN = {"left": 80, "right": 250, "top": 56, "bottom": 64}
PALETTE = ((31, 119, 180), (255, 127, 14), (44, 160, 44), (214, 39, 40), (148, 103, 189),
           (140, 86, 75), (227, 119, 194), (127, 127, 127), (188, 189, 34), (23, 190, 207))
INK, GRID, FLOOR, FLOOR_EDGE = (40, 40, 40), (226, 226, 226), (178, 178, 178), (120, 120, 120)
SWEPT_ALPHA = 80  # of 255: how strongly swept cells are tinted
LEGEND_ROWS = 22  # more tracks than this (a large sweep) are summed up in one row


@dataclass
class Swept:
    """Cells a robot's footprint swept over an area: ``mask`` [iy, ix] of ``cell``-metre squares
    from (x0, y0), and the area's outline."""

    x0: float
    y0: float
    cell: float
    mask: object  # a numpy bool array
    area: list[Point]


@dataclass
class Track:
    """One robot's path: ground truth and odometry (mapped into the world), both in metres."""

    label: str
    true: list[Point] = field(default_factory=list)
    odom: list[Point] = field(default_factory=list)
    scan: list[Point] = field(default_factory=list)  # its lidar's last returns, world x, y
    swept: list[Swept] = field(default_factory=list)  # coverage: what its footprint swept


def render(tracks: list[Track], floor: list[Part], out: Path, title: str, subtitle: str = "") -> None:
    """Draw the tracks over the floor plan and write the PNG atomically."""
    canvas = _Canvas(_bounds(tracks, floor))
    canvas.grid_and_axes(grid=True)
    canvas.floor(floor)  # over the grid: obstacles hide it, as furniture hides floor tiles
    for i, track in enumerate(tracks):
        for swept in track.swept:
            canvas.swept(swept, PALETTE[i % len(PALETTE)])
    canvas.grid_and_axes(grid=False)
    for i, track in enumerate(tracks):
        if track.scan:
            canvas.dots(track.scan, PALETTE[i % len(PALETTE)])
    for i, track in enumerate(tracks):
        color = PALETTE[i % len(PALETTE)]
        if len(track.odom) > 1:
            canvas.dashed(track.odom, color)
        if track.true:
            canvas.solid(track.true, color)
            canvas.start_end(track.true, color)
    canvas.legend(tracks, any(len(t.odom) > 1 for t in tracks), bool(floor), any(t.scan for t in tracks),
                  any(t.swept for t in tracks))
    canvas.text((MARGIN["left"], 14), title, size=20)
    if subtitle:
        canvas.text((MARGIN["left"], 36), subtitle, size=13, fill=(90, 90, 90))
    # Up-filtered PNG at zlib level 1 (plot.png): a third of Pillow's encoding time, same pixels.
    png = encode_rgb(canvas.image.reduce(SS))
    # Atomic, not flushed to disk: summary.json, written last, is the run's record that is.
    write_bytes_atomic(out, png, durable=False)


def placement(tracks: list[Track], floor: list[Part]):
    """Where a world point (x, y) lands in the picture ``render`` draws of these tracks and floor
    plan: a function to its pixel (x right, y down, of the saved image)."""
    canvas = _Canvas(_bounds(tracks, floor))
    return lambda p: tuple(v / SS for v in canvas.px(p))


def preload() -> None:
    """Load the fonts a picture uses (13 and 20 points) and what encoding imports, ahead of the
    first picture (a sweep's fork server, once for all its workers)."""
    for size in (13, 20):
        _font(size)
    encode_rgb(Image.new("RGB", (1, 1)))


@functools.lru_cache(maxsize=None)
def _font(size: int):
    """Pillow's default font at ``size`` points (times SS), loaded once a process: a sweep
    worker draws a picture per run."""
    try:
        return ImageFont.load_default(size=size * SS)
    except (TypeError, OSError):  # Pillow without FreeType: its small bitmap font
        return ImageFont.load_default()


def _bounds(tracks: list[Track], floor: list[Part]) -> tuple[float, float, float, float]:
    areas = [p for t in tracks for s in t.swept for p in s.area]
    polygons = [part for part in floor if not isinstance(part, MeshShadow)]
    points = [p for t in tracks for p in (*t.true, *t.odom, *t.scan)] + [p for poly in polygons for p in poly] + areas
    for mesh in (part for part in floor if isinstance(part, MeshShadow)):
        extent = mesh.extent()
        if extent is not None:  # its box's corners: the same extremes
            points += [(extent[0], extent[2]), (extent[1], extent[3])]
    xs = [p[0] for p in points]
    ys = [p[1] for p in points]
    if not xs:
        return -1.0, -1.0, 1.0, 1.0
    x0, x1, y0, y1 = min(xs), max(xs), min(ys), max(ys)
    pad = max(0.5, 0.06 * max(x1 - x0, y1 - y0))  # room for markers; at least 2 m of view
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    hx, hy = max((x1 - x0) / 2 + pad, 1.0), max((y1 - y0) / 2 + pad, 1.0)
    return cx - hx, cy - hy, cx + hx, cy + hy


def nice_step(span: float, target: int = 8) -> float:
    """A tick spacing of 1, 2 or 5 times a power of ten giving about ``target`` ticks."""
    raw = span / max(1, target)
    power = 10.0 ** math.floor(math.log10(raw))
    return next(m * power for m in (1, 2, 5, 10) if m * power >= raw)


def dash_runs(points: list[Point], dash: float, gap: float) -> list[list[Point]]:
    """The pieces of a polyline that a dash pattern (``dash`` on, ``gap`` off) leaves visible."""
    runs, run, pos = [], [points[0]], 0.0  # pos: how far into the current dash + gap period
    for (ax, ay), (bx, by) in zip(points, points[1:]):
        length, done = math.hypot(bx - ax, by - ay), 0.0
        while length - done > 1e-9:
            on = pos < dash
            take = min((dash if on else dash + gap) - pos, length - done)
            done, pos = done + take, pos + take
            point = (ax + (bx - ax) * done / length, ay + (by - ay) * done / length)
            if on:
                run.append(point)
                if pos >= dash - 1e-9:
                    runs.append(run)
            elif pos >= dash + gap - 1e-9:
                run, pos = [point], 0.0
    if pos < dash and len(run) > 1:
        runs.append(run)
    return runs


class _Canvas:
    """World metres to pixels with one scale for both axes, and the drawing helpers."""

    def __init__(self, bounds: tuple[float, float, float, float]):
        self.image = Image.new("RGB", (WIDTH * SS, HEIGHT * SS), "white")
        self.draw = ImageDraw.Draw(self.image)
        x0, y0, x1, y1 = bounds
        left, top = MARGIN["left"], MARGIN["top"]
        width, height = WIDTH - left - MARGIN["right"], HEIGHT - top - MARGIN["bottom"]
        self.scale = min(width / (x1 - x0), height / (y1 - y0))  # pixels per metre
        # Centre the world box; the plot area takes the whole box so the grid fills it.
        cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
        self.x0, self.x1 = cx - width / 2 / self.scale, cx + width / 2 / self.scale
        self.y0, self.y1 = cy - height / 2 / self.scale, cy + height / 2 / self.scale
        self.box = (left, top, left + width, top + height)

    def px(self, p: Point) -> Point:
        """Pixel position (already times SS) of a world point."""
        return ((self.box[0] + (p[0] - self.x0) * self.scale) * SS,
                (self.box[3] - (p[1] - self.y0) * self.scale) * SS)

    def text(self, xy: Point, text: str, size: int = 13, fill=INK, anchor: str = "la") -> None:
        self.draw.text((xy[0] * SS, xy[1] * SS), text, fill=fill, font=_font(size), anchor=anchor)

    def vertical_text(self, centre: Point, text: str, size: int = 13) -> None:
        """Text turned 90 degrees counter-clockwise (an axis label), centred on ``centre``."""
        font = _font(size)
        left, top, right, bottom = self.draw.textbbox((0, 0), text, font=font)
        tile = Image.new("L", (right - left + 4, bottom - top + 4), 0)
        ImageDraw.Draw(tile).text((2 - left, 2 - top), text, fill=255, font=font)
        tile = tile.rotate(90, expand=True)
        self.image.paste(INK, (int(centre[0] * SS - tile.width / 2), int(centre[1] * SS - tile.height / 2)), tile)

    def floor(self, parts: list[Part]) -> None:
        shapes = sum(len(part) if isinstance(part, MeshShadow) else 1 for part in parts)
        outline = shapes < 2000  # a mesh's triangles are filled only: edges would be noise
        for part in parts:
            if isinstance(part, MeshShadow):
                self._mesh(part, outline)
                continue
            points = [self.px(p) for p in part]
            if len(points) == 2:  # an upright face seen edge-on
                self.draw.line(points, fill=FLOOR_EDGE, width=2 * SS)
            else:
                self.draw.polygon(points, fill=FLOOR, outline=FLOOR_EDGE if outline else None,
                                  width=SS if outline else 0)

    def _mesh(self, shadow: MeshShadow, outline: bool) -> None:
        """A mesh's shadow: its triangles filled, then its faces seen edge-on as lines."""
        for xy in self._pixels(shadow.triangles):
            self.draw.polygon(xy, fill=FLOOR, outline=FLOOR_EDGE if outline else None, width=SS if outline else 0)
        for xy in self._pixels(shadow.segments):
            self.draw.line(xy, fill=FLOOR_EDGE, width=2 * SS)

    def _pixels(self, shapes) -> list[list[float]]:
        """``px`` of every corner of ``shapes`` (numpy (n, corners, 2)) at once, the same
        arithmetic: each shape as a flat [x, y, x, y, ...] list."""
        x = (self.box[0] + (shapes[:, :, 0] - self.x0) * self.scale) * SS
        y = (self.box[3] - (shapes[:, :, 1] - self.y0) * self.scale) * SS
        flat = shapes.copy()
        flat[:, :, 0], flat[:, :, 1] = x, y
        return flat.reshape(len(shapes), 2 * shapes.shape[1]).tolist()

    def swept(self, swept: Swept, color) -> None:
        """The swept cells, tinted in the robot's colour, and the area's outline."""
        import numpy as np

        ny, nx = swept.mask.shape
        left, top = self.px((swept.x0, swept.y0 + ny * swept.cell))
        right, bottom = self.px((swept.x0 + nx * swept.cell, swept.y0))
        size = (max(1, round(right - left)), max(1, round(bottom - top)))
        tile = Image.fromarray(np.flipud(swept.mask).astype(np.uint8) * SWEPT_ALPHA, mode="L")
        self.image.paste(color, (round(left), round(top)), tile.resize(size, Image.NEAREST))
        outline = [self.px(p) for p in swept.area]
        self.draw.line(outline + outline[:1], fill=color, width=SS)

    def grid_and_axes(self, grid: bool) -> None:
        """Grid lines at the ticks (``grid``), else the frame, tick labels and axis names."""
        step = nice_step(max(self.x1 - self.x0, self.y1 - self.y0))
        decimals = max(0, -math.floor(math.log10(step) + 1e-9))
        left, top, right, bottom = (v * SS for v in self.box)
        for k in range(math.ceil(self.x0 / step), math.floor(self.x1 / step) + 1):
            x = self.px((k * step, 0.0))[0]
            if grid:
                self.draw.line([(x, top), (x, bottom)], fill=GRID, width=SS)
            else:
                self.text((x / SS, self.box[3] + 6), f"{k * step:.{decimals}f}", anchor="ma")
        for k in range(math.ceil(self.y0 / step), math.floor(self.y1 / step) + 1):
            y = self.px((0.0, k * step))[1]
            if grid:
                self.draw.line([(left, y), (right, y)], fill=GRID, width=SS)
            else:
                self.text((self.box[0] - 8, y / SS), f"{k * step:.{decimals}f}", anchor="rm")
        if grid:
            return
        self.draw.rectangle([left, top, right, bottom], outline=INK, width=SS)
        self.text(((self.box[0] + self.box[2]) / 2, self.box[3] + 28), "x (m)", anchor="ma")
        self.vertical_text((18, (self.box[1] + self.box[3]) / 2), "y (m)")

    def solid(self, points: list[Point], color) -> None:
        self.draw.line([self.px(p) for p in points], fill=color, width=2 * SS, joint="curve")

    def dashed(self, points: list[Point], color, dash: float = 7.0, gap: float = 5.0) -> None:
        """A polyline drawn in dashes of ``dash`` pixels with ``gap`` between them."""
        for run in dash_runs([self.px(p) for p in points], dash * SS, gap * SS):
            self.draw.line(run, fill=color, width=int(1.5 * SS))

    def dots(self, points: list[Point], color) -> None:
        """Lidar returns: small filled squares."""
        r = SS
        for x, y in (self.px(p) for p in points):
            self.draw.rectangle([x - r, y - r, x + r, y + r], fill=color)

    def start_end(self, points: list[Point], color) -> None:
        r = 5 * SS
        x, y = self.px(points[0])
        self.draw.ellipse([x - r, y - r, x + r, y + r], fill="white", outline=color, width=2 * SS)
        x, y = self.px(points[-1])
        self.draw.rectangle([x - r, y - r, x + r, y + r], fill=color, outline=INK, width=SS)

    def legend(self, tracks: list[Track], odometry: bool, floor: bool, scans: bool = False,
               swept: bool = False) -> None:
        x, y = WIDTH - MARGIN["right"] + 24, MARGIN["top"]
        rows: list[tuple[str, object]] = [("true path", "solid")]
        if odometry:
            rows.append(("odometry", "dashed"))
        if scans:
            rows.append(("last lidar scan", "dots"))
        rows += [("start", "start"), ("end", "end")]
        if floor:
            rows.append(("obstacles", "floor"))
        if swept:
            rows.append(("swept (coverage)", "swept"))
        for label, kind in rows:
            self._key(x, y, kind, INK)
            self.text((x + 38, y), label, anchor="lm")
            y += 22
        y += 10
        shown = tracks if len(tracks) <= LEGEND_ROWS else tracks[:LEGEND_ROWS - 1]
        for i, track in enumerate(shown):
            self._key(x, y, "solid", PALETTE[i % len(PALETTE)])
            self.text((x + 38, y), self._fit(track.label, WIDTH - x - 38 - 8), anchor="lm")
            y += 22
        if len(shown) < len(tracks):
            self.text((x, y), f"... and {len(tracks) - len(shown)} more", anchor="lm")

    def _fit(self, text: str, width: float, size: int = 13) -> str:
        """``text``, cut short with an ellipsis to fit ``width`` pixels."""
        font = _font(size)
        if font.getlength(text) <= width * SS:
            return text
        while text and font.getlength(text + "...") > width * SS:
            text = text[:-1]
        return text + "..."

    def _key(self, x: float, y: float, kind, color) -> None:
        s = SS
        if kind in ("solid", "dashed"):
            if kind == "solid":
                self.draw.line([(x * s, y * s), ((x + 28) * s, y * s)], fill=color, width=2 * s)
            else:
                for a in (0, 12, 24):
                    self.draw.line([((x + a) * s, y * s), ((x + min(a + 7, 28)) * s, y * s)], fill=color,
                                   width=int(1.5 * s))
        elif kind == "dots":
            for a in (2, 9, 16, 23):
                self.draw.rectangle([(x + a) * s, (y - 1) * s, (x + a + 2) * s, (y + 1) * s], fill=color)
        elif kind == "floor":
            self.draw.rectangle([x * s, (y - 6) * s, (x + 28) * s, (y + 6) * s], fill=FLOOR, outline=FLOOR_EDGE)
        elif kind == "swept":
            tint = tuple(round(255 + (c - 255) * SWEPT_ALPHA / 255) for c in PALETTE[0])
            self.draw.rectangle([x * s, (y - 6) * s, (x + 28) * s, (y + 6) * s], fill=tint, outline=PALETTE[0])
        else:
            r, cx = 5 * s, (x + 14) * s
            box = [cx - r, y * s - r, cx + r, y * s + r]
            if kind == "start":
                self.draw.ellipse(box, fill="white", outline=color, width=2 * s)
            else:
                self.draw.rectangle(box, fill=color, outline=INK, width=s)
