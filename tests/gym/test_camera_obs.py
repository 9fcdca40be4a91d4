"""The Gymnasium env's camera observation: SB3's image conventions, renders at the camera's rate."""

from __future__ import annotations

import numpy as np
import pytest

from mobot_cli.errors import UsageError
from mobot_cli.gym import MobotEnv


def test_the_camera_is_a_uint8_hwc_image_and_a_depth_map_in_a_dict():
    env = MobotEnv("house", "mobot", args={"camera": "true"}, camera=True, scan=False, pose=(-3.0, -2.5, 0.0),
                   goal=(0.0, -2.5))
    try:
        space = env.observation_space
        assert space["image"].shape == (240, 320, 3) and space["image"].dtype == np.uint8
        assert space["depth"].shape == (240, 320, 1) and float(space["depth"].high.max()) == 1.0
        obs, _ = env.reset(seed=3)
        assert space.contains(obs)
        first = obs["image"].copy()
        for _ in range(3):
            obs, *_ = env.step([1.0, 0.0])
        assert space.contains(obs) and not np.array_equal(first, obs["image"])  # it drove: the view changed
        again, _ = env.reset(seed=3)
        assert np.array_equal(again["image"], first)  # the same episode, the same pixels
    finally:
        env.close()


def test_a_robot_without_a_camera_is_refused_before_any_world():
    with pytest.raises(UsageError, match="has no camera"):
        MobotEnv("empty", "mobot", camera=True, scan=False)
