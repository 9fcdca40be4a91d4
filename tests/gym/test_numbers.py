"""NaN, infinities and absurd numbers given to the Gymnasium env: mobot's own error before the
world is touched, and the episode's run folder still gets its summary (issue 26)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

pytest.importorskip("gymnasium", reason="the gym extra is not installed: pip install -e '.[gym]'")

from mobot_cli.errors import MobotError, UsageError  # noqa: E402
from mobot_cli.gym import MobotEnv  # noqa: E402

numbers = st.floats(allow_nan=True, allow_infinity=True, width=32) | st.sampled_from([math.nan, math.inf, -math.inf])


@pytest.fixture(scope="module")
def env(tmp_path_factory):
    out = tmp_path_factory.mktemp("gym")
    environment = MobotEnv(scan=False, out=out)
    environment.reset(seed=1)
    yield environment
    environment.close()
    summary = json.loads((out / "episode_0000" / "summary.json").read_text())
    assert summary["status"] == "ok"


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(action=st.lists(numbers, min_size=0, max_size=3))
def test_actions_are_two_finite_numbers_or_refused_before_the_world_moves(env, action):
    step = env._sim.step_count
    if len(action) == 2 and all(math.isfinite(v) for v in action):
        obs, reward, *_ = env.step(np.array(action, np.float32))
        assert np.all(np.isfinite(obs)) and math.isfinite(reward)
        assert env._sim.step_count == step + env._steps_per_action
        return
    with pytest.raises(UsageError, match=r"^step: the action"):
        env.step(np.array(action, np.float32))
    assert env._sim.step_count == step


@pytest.mark.parametrize("setting", ["max_linear", "max_angular", "control_hz", "goal_tolerance", "settle"])
@pytest.mark.parametrize("value", [math.nan, math.inf, -1.0, 1e308])
def test_settings_are_checked_before_a_world_exists(setting, value):
    with pytest.raises(MobotError, match=rf"^{setting}: "):
        MobotEnv(scan=False, **{setting: value})
