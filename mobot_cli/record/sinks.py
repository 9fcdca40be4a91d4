"""Writers for the run folder. Each sink consumes the timeline's records; none drives it.

A sink is told when a robot arrives (``spawned``, with its plan) and leaves (``deleted``),
takes ``write(sample)`` for every sample and ``reading(key, reading)`` for every sensor
reading, and finishes its files in ``close()``. Robots are named by their name in the record
(``<name>__2`` for a name used again in a live world).
"""

from __future__ import annotations

import os
from pathlib import Path

from mobot_cli.plan import Plan
from mobot_cli.sim.state import RobotState
from mobot_cli.timeline.records import Sample, Sink

CSV_COLUMNS = ("t",) + RobotState.CSV_FIELDS
FLUSH_EVERY_ROWS = 50


_ROW = ",".join(["%.6f"] * len(CSV_COLUMNS)) + "\n"


def csv_row(values: tuple[float, ...]) -> str:
    """One CSV line: six decimals per value, never '-0.000000', formatted in one go (it is hot)."""
    # Every '-' in the line is a value's sign and every value has six decimals, so
    # '-0.000000' can only be a whole value that rounded to zero.
    return (_ROW % values).replace("-0.000000", "0.000000")


class OdomCsv:
    """One robot's odometry log, written every few rows so a killed run keeps what it had.

    Rows wait in a list and reach the file together: the file only grows at these writes, so a
    killed run leaves whole rows, never half a line. A write that fails part-way (a full disk,
    the size limit) is cut back to the last whole row before the error goes up.
    """

    def __init__(self, path: Path):
        path.parent.mkdir(parents=True, exist_ok=True)
        self.path = path
        self._fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o666)
        self._size = 0  # bytes of whole rows in the file
        self._rows: list[str] = []
        try:
            self._write((",".join(CSV_COLUMNS) + "\n").encode())
        except OSError:
            os.close(self._fd)
            raise

    def write(self, t: float, state: RobotState) -> None:
        rows = self._rows
        rows.append(csv_row((t, *state.row())))
        if len(rows) >= FLUSH_EVERY_ROWS:
            self.flush()

    def flush(self) -> None:
        """Write the waiting rows."""
        if self._rows:
            data = "".join(self._rows).encode()
            self._rows.clear()
            self._write(data)

    def close(self) -> None:
        try:
            self.flush()
        finally:
            os.close(self._fd)

    def _write(self, data: bytes) -> None:
        view = memoryview(data)
        try:
            while view:
                view = view[os.write(self._fd, view):]
        except OSError as exc:
            try:
                os.ftruncate(self._fd, self._size)  # no torn row: back to the last whole one
            except OSError:
                pass
            raise named(exc, self.path) from None
        self._size += len(data)


class CsvSink(Sink):
    """``odom/<robot>.csv`` for every robot, opened on the robot's first sample."""

    def __init__(self, plan: Plan, out_dir: Path):
        self._rate = plan.physics.rate_hz
        self._dir = out_dir / "odom"
        self._files: dict[str, OdomCsv] = {}

    def write(self, sample: Sample) -> None:
        t = sample.step / self._rate
        for name, state in sample.states.items():
            if name not in self._files:
                self._files[name] = OdomCsv(self._dir / f"{name}.csv")
            self._files[name].write(t, state)

    def close(self) -> None:
        for csv in self._files.values():
            csv.close()


def named(exc: OSError, path: Path) -> OSError:
    """``exc`` naming the file it happened to, for the error message."""
    if exc.filename is None:
        exc.filename = str(path)
    return exc
