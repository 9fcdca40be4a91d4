"""Writers for the run folder: odometry CSV per robot and an atomic summary.json."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any

from mobot_cli.sim.state import RobotState

CSV_COLUMNS = ("t",) + RobotState.CSV_FIELDS
FLUSH_EVERY_ROWS = 50


def number(value: float) -> str:
    """Fixed six decimals, so that files compare byte for byte; never '-0.000000'."""
    text = f"{value:.6f}"
    return "0.000000" if text == "-0.000000" else text


class OdomCsv:
    """One robot's odometry log, flushed every few rows so a killed run keeps what it had."""

    def __init__(self, path: Path):
        path.parent.mkdir(parents=True, exist_ok=True)
        self._file = path.open("w", encoding="utf-8", newline="\n")
        self._file.write(",".join(CSV_COLUMNS) + "\n")
        self._rows = 0

    def write(self, t: float, state: RobotState) -> None:
        self._file.write(",".join(number(v) for v in (t, *state.row())) + "\n")
        self._rows += 1
        if self._rows % FLUSH_EVERY_ROWS == 0:
            self._file.flush()

    def close(self) -> None:
        self._file.close()


def write_json_atomic(path: Path, data: dict[str, Any]) -> None:
    """Write JSON to a temporary sibling and rename it into place."""
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(data, indent=2, allow_nan=False, default=_plain) + "\n", encoding="utf-8")
    os.replace(tmp, path)


def write_text_atomic(path: Path, text: str) -> None:
    """Write text to a temporary sibling and rename it into place."""
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text, encoding="utf-8")
    os.replace(tmp, path)


def _plain(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return str(value)
