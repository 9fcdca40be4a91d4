"""SDF shapes PyBullet has no primitive for, as triangle meshes: ``<cone>``, ``<ellipsoid>`` and
``<polyline>``.

Each becomes an OBJ file in the cache (keyed by its numbers) and from there a mesh like any other
(world/geometry.py), so collisions, lidars, cameras, maps and pictures all see it. The shapes are
Gazebo's (gz-common's MeshManager): a cone along z with its base at -length/2 and its apex at
+length/2; an ellipsoid of three radii about its centre; a polyline's closed outline extruded
from z = 0 to ``height``. Round surfaces are polygons within ``ROUND_TOLERANCE`` of the true
one, as the lidar's triangles of round primitives are (common/polygon.py's circle_sides).

A polyline's caps are triangulated by ear clipping, one outline at a time: an outline inside
another is a second prism, not a hole (Gazebo triangulates all of them together and leaves
holes); ``nested`` says when that happens so the reader can warn.
"""

from __future__ import annotations

import math

import numpy as np

from mobot_cli.common.polygon import circle_sides, contains, signed_area

# Sides of a circle at most: an ellipsoid has half as many rings, and PyBullet refuses a mesh of
# about 130,000 vertices (256 x 128 stays well below)
MAX_SIDES = 256


def cone(radius: float, length: float) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and triangles of a cone: base circle at z = -length/2, apex at +length/2."""
    n = circle_sides(radius, MAX_SIDES)
    angles = np.arange(n) * (2.0 * math.pi / n)
    rim = np.stack([radius * np.cos(angles), radius * np.sin(angles), np.full(n, -length / 2.0)], axis=1)
    vertices = np.vstack([rim, [[0.0, 0.0, length / 2.0], [0.0, 0.0, -length / 2.0]]])
    apex, centre = n, n + 1
    faces = []
    for i in range(n):
        j = (i + 1) % n
        faces += [(i, j, apex), (j, i, centre)]
    return vertices, np.array(faces, dtype=np.int64)


def ellipsoid(radii: tuple[float, float, float]) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and triangles of an ellipsoid: a latitude-longitude sphere scaled by the radii."""
    n = circle_sides(max(radii), MAX_SIDES)
    rings = max(n // 2, 8)
    vertices = [(0.0, 0.0, radii[2])]
    for k in range(1, rings):
        polar = math.pi * k / rings
        for i in range(n):
            azimuth = 2.0 * math.pi * i / n
            vertices.append((radii[0] * math.sin(polar) * math.cos(azimuth),
                             radii[1] * math.sin(polar) * math.sin(azimuth), radii[2] * math.cos(polar)))
    vertices.append((0.0, 0.0, -radii[2]))
    bottom = len(vertices) - 1
    faces = []
    for i in range(n):
        j = (i + 1) % n
        faces.append((0, 1 + i, 1 + j))
        last = 1 + (rings - 2) * n
        faces.append((bottom, last + j, last + i))
    for k in range(rings - 2):
        a, b = 1 + k * n, 1 + (k + 1) * n
        for i in range(n):
            j = (i + 1) % n
            faces += [(a + i, b + i, b + j), (a + i, b + j, a + j)]
    return np.array(vertices, dtype=float), np.array(faces, dtype=np.int64)


def polyline(outlines: list[list[tuple[float, float]]], height: float) -> tuple[np.ndarray, np.ndarray, bool]:
    """Vertices and triangles of the outlines extruded from z = 0 to ``height``, and whether an
    outline lies inside another (Gazebo would make it a hole; here it is a prism of its own)."""
    vertices: list[tuple[float, float, float]] = []
    faces: list[tuple[int, int, int]] = []
    rings = [_ring(points) for points in outlines]
    rings = [ring for ring in rings if len(ring) >= 3]
    for ring in rings:
        if signed_area(ring) < 0.0:
            ring.reverse()  # counter-clockwise: caps face out
        base, n = len(vertices), len(ring)
        vertices += [(x, y, 0.0) for x, y in ring] + [(x, y, height) for x, y in ring]
        for a, b, c in _ears(ring):
            faces += [(base + a, base + c, base + b), (base + n + a, base + n + b, base + n + c)]
        for i in range(n):
            j = (i + 1) % n
            faces += [(base + i, base + j, base + n + j), (base + i, base + n + j, base + n + i)]
    nested = any(i != j and contains(rings[j], *rings[i][0]) for i in range(len(rings)) for j in range(len(rings)))
    return np.array(vertices, dtype=float).reshape(-1, 3), np.array(faces, dtype=np.int64).reshape(-1, 3), nested


def _ring(points: list[tuple[float, float]]) -> list[tuple[float, float]]:
    """The outline without repeated points and without a closing copy of its first point (1e-4 m,
    as Gazebo's extrusion closes it)."""
    ring: list[tuple[float, float]] = []
    for point in points:
        if not ring or math.dist(ring[-1], point) > 1e-4:
            ring.append((float(point[0]), float(point[1])))
    while len(ring) > 1 and math.dist(ring[0], ring[-1]) <= 1e-4:
        ring.pop()
    return ring


def _ears(ring: list[tuple[float, float]]) -> list[tuple[int, int, int]]:
    """Triangles of a simple counter-clockwise polygon by ear clipping (O(n^2); outlines are short)."""
    left = list(range(len(ring)))
    out = []
    guard = 0
    while len(left) > 3 and guard < 4 * len(ring) * len(ring):
        guard += 1
        for k in range(len(left)):
            i, j, m = left[k - 1], left[k], left[(k + 1) % len(left)]
            a, b, c = ring[i], ring[j], ring[m]
            if _cross(a, b, c) <= 1e-12:
                continue  # a reflex or flat corner is no ear
            if any(_in_triangle(ring[q], a, b, c) for q in left if q not in (i, j, m)):
                continue
            out.append((i, j, m))
            del left[k]
            break
        else:  # not a simple polygon (it crosses itself): fan the rest, as well as can be done
            break
    out += [(left[0], left[q], left[q + 1]) for q in range(1, len(left) - 1)]
    return out


def _cross(a, b, c) -> float:
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])


def _in_triangle(p, a, b, c) -> bool:
    return _cross(a, b, p) >= 0.0 and _cross(b, c, p) >= 0.0 and _cross(c, a, p) >= 0.0
