"""GetEntityState and SetEntityState: a robot's pose and twist in the world or another robot's frame.

A reference frame is a robot's root link, moving with it: a pose relative to it is
``inv(T_ref) * T``, a twist relative to it is what an observer riding on it sees, in its axes:
``v_rel = R_ref^T (v - v_ref - w_ref x (p - p_ref))`` and ``w_rel = R_ref^T (w - w_ref)``.
"""

from __future__ import annotations

from typing import Any

from mobot_cli.common.transforms import mat_vec, matrix_rpy, quat_matrix, quat_mul
from mobot_cli.sim.entity import Kinematics

Vec = tuple[float, float, float]


def relative(state: Kinematics, ref: Kinematics | None) -> Kinematics:
    """``state`` seen from ``ref`` (None: the world)."""
    if ref is None:
        return state
    m = quat_matrix(ref.orientation)
    d = _sub(state.position, ref.position)
    wr = ref.angular
    v = _sub(_sub(state.linear, ref.linear), _cross(wr, d))
    qr = ref.orientation
    orientation = quat_mul((-qr[0], -qr[1], -qr[2], qr[3]), state.orientation)
    return Kinematics(_rotate_back(m, d), orientation, _rotate_back(m, v), _rotate_back(m, _sub(state.angular, wr)))


def world_twist(position: Vec, linear: Vec, angular: Vec, ref: Kinematics | None) -> tuple[Vec, Vec]:
    """A twist given in ``ref``'s frame for a body at world ``position``, in the world frame."""
    if ref is None:
        return linear, angular
    m = quat_matrix(ref.orientation)
    w = _add(ref.angular, mat_vec(m, angular))
    v = _add(_add(ref.linear, _cross(ref.angular, _sub(position, ref.position))), mat_vec(m, linear))
    return v, w


def fields(state: Kinematics) -> dict[str, Any]:
    """Reply fields: pose (x, y, z, roll, pitch, yaw and quat [x, y, z, w]) and twist."""
    x, y, z = state.position
    qx, qy, qz, qw = state.orientation
    roll, pitch, yaw = matrix_rpy(quat_matrix(state.orientation))
    return {"pose": {"x": x, "y": y, "z": z, "roll": roll, "pitch": pitch, "yaw": yaw,
                     "quat": [qx, qy, qz, qw]},
            "twist": {"linear": _xyz(state.linear), "angular": _xyz(state.angular)}}


def _xyz(v: Vec) -> dict[str, float]:
    return {"x": v[0], "y": v[1], "z": v[2]}


def _sub(a: Vec, b: Vec) -> Vec:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _add(a: Vec, b: Vec) -> Vec:
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def _cross(a: Vec, b: Vec) -> Vec:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _rotate_back(m, v: Vec) -> Vec:
    """R^T v."""
    return tuple(m[0][i] * v[0] + m[1][i] * v[1] + m[2][i] * v[2] for i in range(3))  # type: ignore
