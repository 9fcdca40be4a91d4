"""Rotations and poses: conversions agree with each other and with PyBullet, compositions with
matrices; conventions are ROS's (x, y, z, w quaternions, fixed-axis roll-pitch-yaw)."""

from __future__ import annotations

import math

import pybullet
import pytest
from hypothesis import given
from hypothesis import strategies as st

from mobot_cli.common.transforms import (
    Frame,
    Planar,
    compose_poses,
    mat_vec,
    matrix_rpy,
    odom_origin,
    pose_point,
    quat_from_matrix,
    quat_from_rpy,
    quat_matrix,
    quat_mul,
    rpy_matrix,
    yaw_quat,
)

angle = st.floats(-math.pi, math.pi, allow_nan=False)
small = st.floats(-1.5, 1.5, allow_nan=False)  # pitch away from gimbal lock
coord = st.floats(-100.0, 100.0, allow_nan=False)


def close(a, b, tol=1e-9):
    return all(abs(x - y) <= tol for x, y in zip(a, b, strict=True))


def flat(m):
    return [v for row in m for v in row]


@given(angle, small, angle)
def test_rpy_matrix_quat_agree_with_pybullet_and_round_trip(roll, pitch, yaw):
    q = quat_from_rpy(roll, pitch, yaw)
    assert close(q, pybullet.getQuaternionFromEuler((roll, pitch, yaw)), 1e-12)
    assert close(flat(quat_matrix(q)), pybullet.getMatrixFromQuaternion(q))
    assert close(flat(rpy_matrix(roll, pitch, yaw)), flat(quat_matrix(q)))
    assert close(matrix_rpy(rpy_matrix(roll, pitch, yaw)), (roll, pitch, yaw), 1e-7)
    back = quat_from_matrix(rpy_matrix(roll, pitch, yaw))
    assert back[3] >= 0.0 and close(back, q if q[3] >= 0 else tuple(-c for c in q))


def test_quaternions_from_matrices_have_one_sign_and_no_negative_zero():
    half_turn = quat_from_matrix(rpy_matrix(0.0, 0.0, math.pi))
    assert half_turn[3] >= 0.0 and close(half_turn, (0.0, 0.0, 1.0, 0.0))
    assert [math.copysign(1.0, c) for c in quat_from_matrix(rpy_matrix(0, 0, 0))] == [1.0] * 4
    assert yaw_quat(math.pi / 2) == pytest.approx((0.0, 0.0, math.sqrt(0.5), math.sqrt(0.5)))


@given(angle, small, angle, coord, coord, coord, angle, angle)
def test_compositions_agree_in_both_forms(roll, pitch, yaw, x, y, z, yaw2, roll2):
    a_quat, b_quat = quat_from_rpy(roll, pitch, yaw), quat_from_rpy(roll2, 0.0, yaw2)
    xyz, quat = compose_poses(((x, y, z), a_quat), ((1.0, 2.0, 3.0), b_quat))
    a = Frame(rpy_matrix(roll, pitch, yaw), (x, y, z))
    ab = a.compose(Frame(rpy_matrix(roll2, 0.0, yaw2), (1.0, 2.0, 3.0)))
    assert close(xyz, ab.pos) and close(flat(quat_matrix(quat)), flat(ab.rot))
    assert close(pose_point((x, y, z), a_quat, (0.5, -1.0, 2.0)), a.point((0.5, -1.0, 2.0)))
    assert close(quat_mul(a_quat, (0.0, 0.0, 0.0, 1.0)), a_quat, 0.0)
    assert close(mat_vec(rpy_matrix(0, 0, math.pi / 2), (1.0, 0.0, 0.0)), (0.0, 1.0, 0.0))


@given(coord, coord, angle, coord, coord, angle)
def test_odometry_maps_back_onto_the_truth(true_x, true_y, true_yaw, odom_x, odom_y, odom_yaw):
    origin = odom_origin(true_x, true_y, true_yaw, odom_x, odom_y, odom_yaw)
    assert close(origin(odom_x, odom_y), (true_x, true_y), 1e-9)
    assert Planar(1.0, 2.0, math.pi / 2)(1.0, 0.0) == pytest.approx((1.0, 3.0))
