"""nav2 map_server's map files: ``map.yaml`` beside a trinary ``map.pgm`` (binary P5 greyscale).

The grid is an OccupancyGrid's data: int8 cells, 0 free, 100 occupied, -1 unknown, row 0 at the
map's origin (its lowest y). The image holds the same rows the other way up (row 0 at the top),
as map_server's loader flips them back (map_io.cpp: ``data[width * (height - y - 1) + x]``).
Pixels as nav2's map_saver writes them in trinary mode: 254 free, 0 occupied, 205 unknown.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

FREE, OCCUPIED, UNKNOWN = 0, 100, -1  # OccupancyGrid cell values
PIXELS = {FREE: 254, OCCUPIED: 0, UNKNOWN: 205}
OCCUPIED_THRESH, FREE_THRESH = 0.65, 0.25  # map_saver's defaults


@dataclass(frozen=True)
class MapFiles:
    """What ``write_map`` wrote."""

    yaml: Path
    image: Path


def grid_cells(occupied: np.ndarray) -> np.ndarray:
    """A boolean occupancy mask (row 0 at the lowest y) as OccupancyGrid data: 0 or 100, int8."""
    return np.where(occupied, OCCUPIED, FREE).astype(np.int8)


def pgm_bytes(cells: np.ndarray) -> bytes:
    """The P5 image of ``cells`` (OccupancyGrid rows, row 0 at the lowest y): row 0 at the top."""
    pixels = np.full(cells.shape, PIXELS[UNKNOWN], dtype=np.uint8)
    pixels[cells == FREE] = PIXELS[FREE]
    pixels[cells == OCCUPIED] = PIXELS[OCCUPIED]
    height, width = cells.shape
    return f"P5\n{width} {height}\n255\n".encode("ascii") + np.flipud(pixels).tobytes()


def yaml_text(image: str, resolution: float, origin: tuple[float, float, float]) -> str:
    """The metadata map_server reads (nav2's keys, in map_saver's order)."""
    x, y, yaw = (_number(v) for v in origin)
    return (f"image: {image}\nmode: trinary\nresolution: {_number(resolution)}\norigin: [{x}, {y}, {yaw}]\n"
            f"negate: 0\noccupied_thresh: {OCCUPIED_THRESH}\nfree_thresh: {FREE_THRESH}\n")


def write_map(out_dir: Path, cells: np.ndarray, resolution: float, origin: tuple[float, float, float],
              name: str = "map") -> MapFiles:
    """Write ``NAME.yaml`` and ``NAME.pgm`` into ``out_dir`` (created); OSError when it cannot."""
    out_dir.mkdir(parents=True, exist_ok=True)
    image, meta = out_dir / f"{name}.pgm", out_dir / f"{name}.yaml"
    image.write_bytes(pgm_bytes(cells))
    meta.write_text(yaml_text(image.name, resolution, origin), encoding="utf-8")
    return MapFiles(meta, image)


def _number(value: float) -> str:
    """A float as YAML reads it back exactly (repr), without a negative zero."""
    value = float(value) + 0.0
    if not math.isfinite(value):
        raise ValueError(f"map metadata must be finite, not {value}")
    return repr(round(value, 9))


def occupancy_grid_cdr(cells: np.ndarray, resolution: float, origin: tuple[float, float, float],
                       stamp: tuple[int, int], frame_id: str = "map") -> bytes:
    """nav_msgs/OccupancyGrid in CDR, as map_server publishes a map: rows from the origin up,
    ``map_load_time`` the stamp, the origin's yaw as a quaternion about z."""
    from mobot_cli.ros.sensor_cdr import CdrWriter

    height, width = cells.shape
    x, y, yaw = origin
    out = CdrWriter().header(stamp, frame_id).pack("iI", *stamp).pack("f", resolution).pack("II", width, height)
    out.pack("7d", x, y, 0.0, 0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))
    return out.sequence(np.ascontiguousarray(cells, dtype=np.int8).reshape(-1), 1).bytes()
