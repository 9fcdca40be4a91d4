"""``DIR/history.jsonl`` of a live world (`mobot serve --out DIR`): one line per spawn, delete,
cmd and skipped scenario event, refused ones too.

Request fields come from clients, so a line keeps them bounded: a string longer than
MAX_CHARS is cut and marked with its length, lists and objects keep their first MAX_ITEMS
items, and a line still longer than MAX_LINE has each structured field cut to a piece of its
JSON text. Everything else in DIR is the run folder `mobot run` writes (record/recording.py).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

MAX_CHARS = 256
MAX_ITEMS = 32
MAX_DEPTH = 4
MAX_LINE = 4096  # a longer line has each structured field cut to MAX_CHARS of its JSON text


class History:
    """Appends one JSON line per thing that happened, flushed at once (a killed server keeps it)."""

    def __init__(self, out_dir: Path, rate_hz: int):
        self.rate_hz = rate_hz
        self._file = (out_dir / "history.jsonl").open("w", encoding="utf-8")

    def write(self, step: int, record: dict[str, Any]) -> None:
        """One line: the time, the step and the record's fields (bounded)."""
        fields = {str(key): bounded(value) for key, value in record.items()}
        line = json.dumps({"t": step / self.rate_hz, "step": step, **fields}, allow_nan=False)
        if len(line) > MAX_LINE:  # many long items: each field becomes a cut piece of its JSON text
            fields = {key: _squeezed(value) for key, value in fields.items()}
            line = json.dumps({"t": step / self.rate_hz, "step": step, **fields}, allow_nan=False)
        self._file.write(line + "\n")
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


def _squeezed(value: Any) -> Any:
    if not isinstance(value, (dict, list)):
        return value
    return bounded(json.dumps(value, allow_nan=False))
