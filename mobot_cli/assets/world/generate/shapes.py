"""A generated world's obstacles: plain shapes standing on the floor, before any file."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any


@dataclass(frozen=True)
class Obstacle:
    """One static shape standing on the floor: a box (size x, y, z) or a cylinder (radius, length)."""

    name: str
    kind: str  # "box" | "cylinder"
    size: tuple[float, ...]
    x: float
    y: float
    yaw: float = 0.0

    @property
    def height(self) -> float:
        return self.size[2] if self.kind == "box" else self.size[1]


@dataclass(frozen=True)
class Generated:
    """A generated world: its name, obstacles, and what else the kind knows (BARN's free path)."""

    name: str
    obstacles: tuple[Obstacle, ...]
    info: dict[str, Any] = field(default_factory=dict)


def rounded(value: float) -> float:
    """A coordinate as the world file writes it (6 decimals), so that the plan made here and the
    plan loaded from the file hold the same numbers."""
    return float(f"{value:.6f}") + 0.0
