"""An independent reader of map_server files, following nav2_map_server's map_io.cpp rules.

``loadMapYaml`` + ``loadMapFromFile`` (trinary mode): a pixel's shade is its grey value / 255;
its occupancy is ``1 - shade`` (``shade`` when ``negate``); occupied (100) when
``occupied_thresh < occ``, free (0) when ``occ < free_thresh``, else unknown (-1); image row
``y`` (0 at the top) goes to data row ``height - y - 1`` (row 0 at the origin, the lower-left
pixel). Written from those rules for the tests, sharing no code with mobot_cli.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

REQUIRED = ("image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh")


def read_pgm(path: Path) -> np.ndarray:
    """A binary (P5) or plain (P2) PGM's grey values, 0..1, rows top to bottom."""
    data = path.read_bytes()
    fields, pos = [], 0
    while len(fields) < 4:  # magic, width, height, maxval; '#' comments between them
        while data[pos:pos + 1].isspace():
            pos += 1
        if data[pos:pos + 1] == b"#":
            pos = data.index(b"\n", pos) + 1
            continue
        end = pos
        while not data[end:end + 1].isspace():
            end += 1
        fields.append(data[pos:end].decode("ascii"))
        pos = end
    magic, width, height, maxval = fields[0], int(fields[1]), int(fields[2]), int(fields[3])
    pos += 1  # the single whitespace after maxval
    if magic == "P5":
        assert maxval < 256
        pixels = np.frombuffer(data[pos:pos + width * height], dtype=np.uint8)
    else:
        assert magic == "P2"
        pixels = np.array(data[pos:].split(), dtype=np.int64)
    assert pixels.size == width * height, "short image"
    return pixels.reshape(height, width) / float(maxval)


def load_map(yaml_path: Path) -> tuple[np.ndarray, float, tuple[float, float, float]]:
    """OccupancyGrid data (rows from the origin up), resolution and origin, as map_server loads them."""
    meta = yaml.safe_load(yaml_path.read_text())
    missing = [k for k in REQUIRED if k not in meta]
    assert not missing, f"map_server refuses a map yaml without {missing}"
    assert meta.get("mode", "trinary") == "trinary"
    image = Path(meta["image"])
    image = image if image.is_absolute() else yaml_path.parent / image
    shade = read_pgm(image)
    occ = shade if int(meta["negate"]) else 1.0 - shade
    cells = np.full(shade.shape, -1, dtype=np.int8)
    cells[occ > float(meta["occupied_thresh"])] = 100
    cells[occ < float(meta["free_thresh"])] = 0
    height = shade.shape[0]
    data = np.empty_like(cells)
    for y in range(height):
        data[height - y - 1] = cells[y]
    origin = tuple(float(v) for v in meta["origin"])
    assert len(origin) == 3
    return data, float(meta["resolution"]), origin
