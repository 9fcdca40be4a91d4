"""``DIR/history.jsonl`` of a live world (`mobot serve --out DIR`): one line per spawn, delete,
cmd and skipped scenario event, refused ones too.

Request fields come from clients, so a line keeps them bounded: a string longer than
MAX_CHARS is cut and marked with its length, and lists and objects keep their first MAX_ITEMS
items. Everything else in DIR is the run folder `mobot run` writes (run/recording.py).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

MAX_CHARS = 256
MAX_ITEMS = 32
MAX_DEPTH = 4


class History:
    """Appends one JSON line per thing that happened, flushed at once (a killed server keeps it)."""

    def __init__(self, out_dir: Path, rate_hz: int):
        self.rate_hz = rate_hz
        self._file = (out_dir / "history.jsonl").open("w", encoding="utf-8")

    def write(self, step: int, record: dict[str, Any]) -> None:
        """One line: the time, the step and the record's fields (bounded)."""
        line = {"t": step / self.rate_hz, "step": step, **bounded(record)}
        self._file.write(json.dumps(line, allow_nan=False, default=str) + "\n")
        self._file.flush()

    def close(self) -> None:
        self._file.close()


def bounded(value: Any, depth: int = 0) -> Any:
    """``value`` with long strings cut ('...[cut: N chars]') and long or deep containers trimmed."""
    if isinstance(value, str):
        return value if len(value) <= MAX_CHARS else f"{value[:MAX_CHARS]}...[cut: {len(value)} chars]"
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)  # JSON has no NaN or infinity
    if isinstance(value, dict):
        if depth >= MAX_DEPTH:
            return f"{{...{len(value)} keys}}"
        items = list(value.items())
        out = {bounded(str(k)): bounded(v, depth + 1) for k, v in items[:MAX_ITEMS]}
        if len(items) > MAX_ITEMS:
            out["..."] = f"[cut: {len(items)} keys]"
        return out
    if isinstance(value, (list, tuple)):
        if depth >= MAX_DEPTH:
            return f"[...{len(value)} items]"
        out = [bounded(v, depth + 1) for v in value[:MAX_ITEMS]]
        return out + [f"[cut: {len(value)} items]"] if len(value) > MAX_ITEMS else out
    if value is None or isinstance(value, (bool, int, float)):
        return value
    return bounded(str(value), depth)
