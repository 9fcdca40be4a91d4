"""``DIR/movers.csv``: every mover's pose on every log row (docs/movers.md), made at the first row
that has movers (a run without movers has no such file).

Columns ``t, name, x, y, yaw`` (s, m, rad; the ground truth in the world frame), one row per
mover per log row, movers in the order they entered the world: ``pandas.read_csv`` and a
``groupby("name")`` give each one's path.
"""

from __future__ import annotations

from itertools import chain
from pathlib import Path

from mobot_cli.record.sinks import named
from mobot_cli.timeline.records import Sample, Sink

COLUMNS = ("t", "name", "x", "y", "yaw")
FLUSH_EVERY_ROWS = 50


class MoversCsvSink(Sink):
    """Writes movers.csv as the log rows come."""

    def __init__(self, out_dir: Path, rate_hz: int):
        self.path = out_dir / "movers.csv"
        self.rate = rate_hz
        self._file = None
        self._rows: list[str] = []  # log rows waiting to be written, all movers of a row in one string
        self._names: tuple[str, ...] = ()
        self._format = ""

    def write(self, sample: Sample) -> None:
        if not sample.movers:
            return
        if self._file is None:
            try:
                self._file = open(self.path, "w", encoding="utf-8", newline="")  # noqa: SIM115 - closed in close()
                self._file.write(",".join(COLUMNS) + "\n")
            except OSError as exc:
                raise named(exc, self.path) from None
        movers = sample.movers
        names = tuple(movers)
        if names != self._names:  # one format for a whole row of movers: this runs on every log row
            self._names = names
            self._format = "".join(f",{name.replace('%', '%%')},%.6f,%.6f,%.6f\n" for name in names)
        # every mover's line but its time, in one format; the time, the same on each, put in after
        body = (self._format % tuple(chain.from_iterable(movers.values()))).replace("-0.000000", "0.000000")
        t = "%.6f" % (sample.step / self.rate)
        self._rows.append(t + body.replace("\n", "\n" + t)[:-len(t)])
        if len(self._rows) >= FLUSH_EVERY_ROWS:
            self._flush()

    def _flush(self) -> None:
        if self._rows:
            try:
                self._file.write("".join(self._rows))
            except OSError as exc:
                raise named(exc, self.path) from None
            self._rows.clear()

    def close(self) -> None:
        if self._file is not None:
            try:
                self._flush()
            finally:
                self._file.close()
