"""The live world's pace: steps paced to the wall clock, or as fast as it can."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

MAX_LAG = 0.25  # s: a real-time world further behind than this drops the lost time


@dataclass
class Clock:
    """Paces steps to the wall clock at ``rtf`` times real time; ``rtf`` None: as fast as possible."""

    dt: float
    rtf: float | None
    start: float = field(default_factory=time.monotonic)
    count: int = 0
    lags: int = 0  # how often the world fell behind and dropped the lost time

    def due(self) -> float | None:
        """Wall time at which the next step is due; None in fast mode."""
        return None if self.rtf is None else self.start + (self.count + 1) * self.dt / self.rtf

    def restart(self) -> None:
        """Pace from now on (after a pause): the next step is due one period from now."""
        if self.rtf is not None:
            self.start = time.monotonic() - self.count * self.dt / self.rtf

    def stepped(self) -> None:
        """Count a step; a world too far behind starts its clock afresh instead of racing."""
        self.count += 1
        due = self.due()
        if due is not None and time.monotonic() - due > MAX_LAG:
            self.start = time.monotonic() - self.count * self.dt / self.rtf
            self.lags += 1


def pace_text(rtf: float | None) -> str:
    """'real time', '2x real time' or 'fast'."""
    return "fast" if rtf is None else ("real time" if rtf == 1.0 else f"{rtf:g}x real time")
