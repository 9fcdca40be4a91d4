"""GetEntityState's frames: a state seen from a moving robot, and a twist given in its frame."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mobot_cli.common.transforms import quat_from_rpy
from mobot_cli.live.entity_state import fields, relative, world_twist
from mobot_cli.live.lockstep import Lockstep, steps_of
from mobot_cli.live.protocol import Refusal
from mobot_cli.sim.entity import Kinematics


def test_a_point_at_rest_seen_from_a_turning_robot_sweeps_backwards():
    spinner = Kinematics((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0), (0.0, 0.0, 0.0), (0.0, 0.0, 1.0))
    still = Kinematics((1.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    seen = relative(still, spinner)
    assert seen.position == (1.0, 0.0, 0.0)
    assert seen.linear == (0.0, -1.0, 0.0) and seen.angular == (0.0, 0.0, -1.0)


def test_the_world_frame_is_the_state_itself_and_fields_name_every_value():
    state = Kinematics((1.0, 2.0, 0.5), quat_from_rpy(0.0, 0.0, 0.5), (0.3, 0.0, 0.0), (0.0, 0.0, 0.2))
    assert relative(state, None) is state
    out = fields(state)
    assert out["pose"]["yaw"] == pytest.approx(0.5) and out["pose"]["quat"][2] == pytest.approx(math.sin(0.25))
    assert out["twist"] == {"linear": {"x": 0.3, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.2}}


ANGLE = st.floats(-3.0, 3.0)
COORD = st.floats(-50.0, 50.0)
SPEED = st.floats(-5.0, 5.0)
VEC = st.tuples(SPEED, SPEED, SPEED)


@settings(max_examples=300, deadline=None)
@given(st.tuples(COORD, COORD, COORD), st.tuples(ANGLE, ANGLE, ANGLE), VEC, VEC,
       st.tuples(COORD, COORD, COORD), VEC, VEC)
def test_a_twist_given_in_a_frame_reads_back_the_same_in_that_frame(ref_xyz, ref_rpy, ref_v, ref_w, xyz, v, w):
    """set_state's world_twist and get_state's relative are inverses, for any moving frame."""
    ref = Kinematics(ref_xyz, quat_from_rpy(*ref_rpy), ref_v, ref_w)
    linear, angular = world_twist(xyz, v, w, ref)
    seen = relative(Kinematics(xyz, (0.0, 0.0, 0.0, 1.0), linear, angular), ref)
    assert seen.linear == pytest.approx(v, abs=1e-9) and seen.angular == pytest.approx(w, abs=1e-9)


@pytest.mark.parametrize("steps, seconds, count", [(None, None, 1), (7, None, 7), (None, 1.0, 240),
                                                    (None, 0.1, 24), (None, 1 / 240, 1), (None, 2.5, 600)])
def test_steps_of_a_request(steps, seconds, count):
    assert steps_of(steps, seconds, 240) == count


@pytest.mark.parametrize("seconds, text", [(1.001, "240.24 steps at 240 Hz, not a whole number: the nearest is 240"),
                                           (0.001, "the nearest is 1 step(s)"), (1e300, "at most 10000000"),
                                           (math.inf, "at most 10000000")])
def test_durations_that_are_not_whole_steps_are_refused(seconds, text):
    with pytest.raises(Refusal) as caught:
        steps_of(None, seconds, 240)
    assert caught.value.result.name == "INVALID_REQUEST" and text in caught.value.message


def test_a_paused_lockstep_takes_exactly_its_budget():
    control = Lockstep(paused=True)
    assert control.hold() and not control.spend()
    assert control.step(3) == 3 and control.pause() is False  # pausing again keeps the budget
    taken = 0
    while not control.hold():
        assert control.spend()
        taken += 1
    assert taken == 3 and control.fields() == {"state": "paused", "state_code": 2}
    assert control.resume() is True and control.step(5) == 0 and not control.hold() and not control.spend()
    assert control.fields() == {"state": "playing", "state_code": 1}
