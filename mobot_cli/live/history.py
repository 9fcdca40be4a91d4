"""``DIR/history.jsonl`` of a live world (`mobot serve --out DIR`): one line per spawn, delete,
cmd and skipped scenario event, refused ones too.

Everything else in DIR is the run folder `mobot run` writes (run/recording.py).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any


class History:
    """Appends one JSON line per thing that happened, flushed at once (a killed server keeps it)."""

    def __init__(self, out_dir: Path, rate_hz: int):
        self.rate_hz = rate_hz
        self._file = (out_dir / "history.jsonl").open("w", encoding="utf-8")

    def write(self, step: int, record: dict[str, Any]) -> None:
        """One line: the time, the step and the record's fields."""
        line = {"t": step / self.rate_hz, "step": step, **record}
        self._file.write(json.dumps(line, allow_nan=False, default=str) + "\n")
        self._file.flush()

    def close(self) -> None:
        self._file.close()
