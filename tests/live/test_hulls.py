"""A spawned robot's collision meshes reach the world as the convex hulls PyBullet would build
from them, built in the loader: the same shape (real PyBullet), far fewer vertices to load."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pybullet as p
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mobot_cli.common.meshfile import count_faces, read_mesh
from mobot_cli.live.hulls import MAX_HULL_VERTICES, hulled
from tests.live.test_bounds import sheet

INERTIAL = ('<inertial><mass value="{mass}"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" '
            'iyz="0"/></inertial>')


def urdf(mesh: Path, mass: float = 1.0) -> str:
    return (f'<robot name="r"><link name="base">{INERTIAL.format(mass=mass)}<collision><geometry>'
            f'<mesh filename="{mesh}"/></geometry></collision></link></robot>')


def cubes(path: Path, group: str | None) -> Path:
    """Two 0.2 m cubes 0.8 m apart, as two OBJ groups or as one ungrouped mesh."""
    lines, base = [], 0
    for i, dx in enumerate((0.0, 1.0)):
        if group:
            lines.append(f"{group} part{i}")
        lines += [f"v {x + dx} {y} {z}" for x, y, z in itertools.product((0, 0.2), repeat=3)]
        lines += ["f " + " ".join(str(base + k) for k in face)
                  for face in ((1, 2, 4, 3), (5, 7, 8, 6), (1, 5, 6, 2), (3, 4, 8, 7), (1, 3, 7, 5), (2, 6, 8, 4))]
        base += 8
    path.write_text("\n".join(lines) + "\n")
    return path


def in_pybullet(text: str, folder: Path) -> tuple[tuple, int]:
    """(the body's AABB, contacts with a ball in the gap between the cubes) in a fresh PyBullet."""
    cid = p.connect(p.DIRECT)
    try:
        path = folder / f"r{abs(hash(text))}.urdf"
        path.write_text(text)
        uid = p.loadURDF(str(path), flags=p.URDF_USE_INERTIA_FROM_FILE, physicsClientId=cid)
        ball = p.createMultiBody(0, p.createCollisionShape(p.GEOM_SPHERE, radius=0.05, physicsClientId=cid),
                                 basePosition=(0.6, 0.1, 0.1), physicsClientId=cid)
        p.performCollisionDetection(physicsClientId=cid)
        return sum(p.getAABB(uid, -1, physicsClientId=cid), ()), len(p.getContactPoints(uid, ball, physicsClientId=cid))
    finally:
        p.disconnect(cid)


@pytest.mark.parametrize("group", ["o", "g", None])
def test_the_hulls_collide_as_pybullets_own(tmp_path, group):
    text = urdf(cubes(tmp_path / f"two_{group}.obj", group))
    hulls = hulled(text)
    assert hulls != text and "two_" not in hulls
    original, ours = in_pybullet(text, tmp_path), in_pybullet(hulls, tmp_path)
    assert ours[0] == pytest.approx(original[0], abs=1e-6)
    assert ours[1] == original[1] == (0 if group else 1)  # one hull per group; ungrouped, one for all


def test_a_heavy_mesh_becomes_a_small_hull_of_the_same_extent(tmp_path):
    text = urdf(sheet(tmp_path / "heavy.obj", 50_000))
    (mesh,) = [line for line in hulled(text).split('"') if line.endswith(".obj")]
    vertices, faces = read_mesh(mesh)
    assert len(vertices) <= MAX_HULL_VERTICES and len(faces) < 5_000
    assert in_pybullet(hulled(text), tmp_path)[0] == pytest.approx(in_pybullet(text, tmp_path)[0], abs=1e-6)


def test_a_fine_sphere_keeps_an_even_subset_of_its_hull(tmp_path):
    n = 120
    u, v = np.meshgrid(np.linspace(0.05, np.pi - 0.05, n), np.linspace(0, 2 * np.pi, n, endpoint=False), indexing="ij")
    points = np.stack([np.sin(u) * np.cos(v), np.sin(u) * np.sin(v), np.cos(u)], -1).reshape(-1, 3) * 0.2
    path = tmp_path / "sphere.obj"
    path.write_text("".join(f"v {x} {y} {z}\n" for x, y, z in points) +
                    "".join(f"f {i + 1} {i + 2} {i + n + 1}\n" for i in range(len(points) - n - 1)))
    (mesh,) = [line for line in hulled(urdf(path)).split('"') if line.endswith(".obj")]
    vertices, _ = read_mesh(mesh)
    assert len(vertices) == MAX_HULL_VERTICES
    radius = np.linalg.norm(vertices, axis=1)
    assert radius.max() == pytest.approx(0.2, abs=1e-6)  # every kept vertex is one of the sphere's


def test_static_links_and_collada_keep_their_meshes(tmp_path):
    mesh = cubes(tmp_path / "two.obj", None)
    assert hulled(urdf(mesh, mass=0.0)) == urdf(mesh, mass=0.0)
    dae = tmp_path / "m.dae"
    dae.write_text("<COLLADA/>")
    assert hulled(urdf(dae)) == urdf(dae)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.binary(max_size=400), suffix=st.sampled_from([".obj", ".stl", ".dae"]))
def test_any_bytes_are_counted_or_kept_never_a_crash(tmp_path, data, suffix):
    """What a client's mesh file holds is untrusted: counting and hulling it never raise."""
    path = tmp_path / f"m{suffix}"
    path.write_bytes(data)
    assert count_faces(str(path)) >= 0
    text = urdf(path)
    assert hulled(text) == text or ".obj" in hulled(text)
