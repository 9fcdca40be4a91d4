"""Plain polygons in the plane (lists of (x, y)): inside, area, boxes. No numpy: scenario
checks use these at load time, before anything heavy is imported."""

from __future__ import annotations

import math

Point = tuple[float, float]


def contains(polygon, x: float, y: float) -> bool:
    """Whether (x, y) lies inside ``polygon`` (even-odd rule)."""
    inside = False
    n = len(polygon)
    for i in range(n):
        (xa, ya), (xb, yb) = polygon[i], polygon[(i + 1) % n]
        if (ya > y) != (yb > y) and x < xa + (y - ya) * (xb - xa) / (yb - ya):
            inside = not inside
    return inside


def signed_area(polygon) -> float:
    """The shoelace area of a simple polygon: positive when its points go counter-clockwise."""
    n = len(polygon)
    twice = sum(polygon[i][0] * polygon[(i + 1) % n][1] - polygon[(i + 1) % n][0] * polygon[i][1]
                for i in range(n))
    return twice / 2.0


def area(polygon) -> float:
    """The area enclosed by a simple polygon (shoelace formula), whatever its winding."""
    return abs(signed_area(polygon))


ROUND_TOLERANCE = 0.0005  # m: largest gap between a round surface and the polygons standing for it
MIN_SIDES, MAX_SIDES = 16, 512


def circle_sides(radius: float, most: int = MAX_SIDES) -> int:
    """Polygon sides for a circle of ``radius`` (at least MIN_SIDES, at most ``most``) so that no
    side lies further than ROUND_TOLERANCE inside the circle."""
    if radius <= ROUND_TOLERANCE:
        return MIN_SIDES
    return int(min(most, max(MIN_SIDES, math.ceil(math.pi / math.acos(1.0 - ROUND_TOLERANCE / radius)))))


def box_polygon(xmin: float, xmax: float, ymin: float, ymax: float) -> list[Point]:
    """A box as a counter-clockwise polygon."""
    return [(xmin, ymin), (xmax, ymin), (xmax, ymax), (xmin, ymax)]


DEFAULT_FOOTPRINT = (-0.2, 0.2, -0.2, 0.2)  # (xmin, xmax, ymin, ymax), m: a robot whose extent is not known


def footprint_radius(footprint: tuple[float, float, float, float]) -> float:
    """The footprint's circumscribed radius about the robot's origin (it can turn in place within it)."""
    xmin, xmax, ymin, ymax = footprint
    return max(math.hypot(x, y) for x in (xmin, xmax) for y in (ymin, ymax))
