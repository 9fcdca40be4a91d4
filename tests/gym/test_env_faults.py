"""A robot that tips over ends its episode (terminated, info["fault"]) instead of raising."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("gymnasium", reason="the gym extra is not installed: pip install -e '.[gym]'")

from mobot_cli.gym import MobotEnv  # noqa: E402

TALL = Path(__file__).resolve().parents[1] / "run" / "robots" / "base.urdf.xacro"


def test_a_flip_ends_the_episode_and_the_next_one_starts_afresh(tmp_path):
    env = MobotEnv(description=str(TALL), args={"wheelbase": "0.3", "com_z": "1.0"}, goal=(10.0, 0.0),
                   max_linear=3.0, scan=False, out=tmp_path)
    env.reset(seed=0)
    for count in range(1, 31):
        obs, reward, terminated, truncated, info = env.step(np.array([1.0, 0.0], dtype=np.float32))
        if terminated:
            break
    assert terminated and not truncated and count < 30
    fault = info["fault"]
    assert (fault["robot"], fault["kind"]) == ("robot", "tipped_over")
    assert f"tipped over at step {fault['step']}" in fault["message"]
    summary = json.loads((tmp_path / "episode_0000" / "summary.json").read_text())
    assert summary["status"] == "fault" and summary["fault"]["kind"] == "tipped_over"
    obs, _ = env.reset(seed=0)  # a new world, the robot upright at its pose again
    assert obs[:3] == pytest.approx([0.0, 0.0, 0.0], abs=1e-3)
    env.close()
