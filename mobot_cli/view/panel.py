"""The page's side panel: the robot list with live numbers, the selected robot, the camera.

Numbers are sent only when their text changed, at most a few times a second (``every``), so a
table of 25 robots costs the page one small message now and then.
"""

from __future__ import annotations

import html
import math
import time
from dataclasses import dataclass
from typing import Any

# Paths and names; tab10 without its blue, which the bundled robot's body already is.
PALETTE = ((255, 127, 14), (44, 160, 44), (214, 39, 40), (148, 103, 189), (140, 86, 75), (227, 119, 194),
           (127, 127, 127), (188, 189, 34), (23, 190, 207))
NONE = "(none)"


def color_of(index: int) -> tuple[int, int, int]:
    """The colour of the index-th robot's label and paths."""
    return PALETTE[index % len(PALETTE)]


@dataclass
class Row:
    """One robot's line in the list."""

    name: str
    x: float
    y: float
    yaw: float
    odom_error: float
    collisions: int | None
    linear: float
    angular: float


class RobotList:
    """A table of robots and a dropdown that selects one (for teleop and the camera)."""

    def __init__(self, server: Any, every: float = 0.25):
        self.server, self.every = server, every
        self._last_sent, self._text = 0.0, ""
        folder = server.gui.add_folder("Robots")
        with folder:
            self.select = server.gui.add_dropdown("selected", (NONE,), initial_value=NONE)
            self.follow = server.gui.add_checkbox("camera follows", False)
            self.table = server.gui.add_html("<p>no robots yet</p>")
        self.note = ""  # a line under the table
        self.colors: dict[str, tuple[int, int, int]] = {}

    @property
    def selected(self) -> str | None:
        """The selected robot's name, or None."""
        value = self.select.value
        return None if value == NONE else value

    def names(self, names: list[str]) -> None:
        """Offer these robots in the dropdown, keeping the selection while it is still there (the
        first robot when none is)."""
        options = tuple([NONE, *names])
        if tuple(self.select.options) != options:
            keep = self.select.value if self.select.value in names else (names[0] if names else NONE)
            self.select.options = options
            self.select.value = keep

    def show(self, rows: list[Row], force: bool = False) -> None:
        """Send the table if its text changed and ``every`` seconds passed."""
        now = time.monotonic()
        if not force and now - self._last_sent < self.every:
            return
        text = self._html(rows)
        if text != self._text:
            self.table.content = text
            self._text = text
        self._last_sent = now

    def _html(self, rows: list[Row]) -> str:
        if not rows:
            return "<p>no robots in the world</p>"
        head = "".join(f"<th>{h}</th>" for h in ("robot", "x", "y", "yaw", "odom err", "coll.", "v, w"))
        lines = []
        for r in rows:
            r_, g, b = self.colors.get(r.name, (80, 80, 80))
            weight = "font-weight:bold;" if r.name == self.selected else ""
            cells = (f"<td style='color:rgb({r_},{g},{b});{weight}'>{html.escape(r.name)}</td>"
                     + "".join(f"<td>{_num(v)}</td>" for v in (r.x, r.y, r.yaw, r.odom_error))
                     + f"<td>{'' if r.collisions is None else r.collisions}</td>"
                     + f"<td>{_num(r.linear)}, {_num(r.angular)}</td>")
            lines.append(f"<tr>{cells}</tr>")
        note = f"<div style='font-size:10px;color:#888'>{html.escape(self.note)}</div>" if self.note else ""
        return ("<table style='font-size:11px;font-family:monospace;border-spacing:5px 1px;text-align:right;"
                "white-space:nowrap'>"
                f"<tr>{head}</tr>{''.join(lines)}</table>{note}")


def aim_camera(server: Any, lo: tuple[float, ...], hi: tuple[float, ...]) -> None:
    """Look at the middle of an extent from the south-west, above, far enough to see it all."""
    cx, cy = (lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2
    span = max(hi[0] - lo[0], hi[1] - lo[1], 4.0)
    server.initial_camera.look_at = (cx, cy, 0.0)
    server.initial_camera.position = (cx - 0.4 * span, cy - 0.65 * span, 0.7 * span)
    server.initial_camera.up = (0.0, 0.0, 1.0)


def follow(server: Any, x: float, y: float) -> None:
    """Keep every client's camera on (x, y), at the distance and angle the user chose."""
    for client in server.get_clients().values():
        cam = client.camera
        offset = cam.position - cam.look_at
        if not all(math.isfinite(v) for v in offset):
            continue
        with client.atomic():
            cam.look_at = (x, y, float(cam.look_at[2]))
            cam.position = (x + offset[0], y + offset[1], float(cam.look_at[2]) + offset[2])


def _num(v: float) -> str:
    return "nan" if not math.isfinite(v) else f"{v:.2f}"
