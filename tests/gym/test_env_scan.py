"""The Gymnasium environment with a lidar robot: the scan in the observation."""

from __future__ import annotations

import math

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium", reason="the gym extra is not installed: pip install -e '.[gym]'")

from gymnasium import spaces  # noqa: E402
from gymnasium.utils.env_checker import check_env  # noqa: E402

from mobot_cli.gym import ENV_ID, MobotEnv  # noqa: E402
from tests.sim.sensor_world import HALF_X, HALF_Y, ROOM_SDF  # noqa: E402

LIDAR = {"lidar": "true"}
NOISE = 0.01 + 0.01  # the bundled lidar's noise stddev and range resolution


@pytest.fixture
def room(tmp_path):
    path = tmp_path / "room.sdf"
    path.write_text(ROOM_SDF)
    return path


def test_a_lidar_robot_passes_the_env_checker_with_a_dict_observation():
    env = gymnasium.make("mobot_cli.gym:" + ENV_ID, args=LIDAR, normalize=False).unwrapped
    space = env.observation_space
    assert isinstance(space, spaces.Dict) and list(space) == ["goal", "odom", "scan"]
    assert space["scan"].shape == (360,) and space["scan"].low.min() == 0.0 and space["scan"].high.max() == 12.0
    assert space["odom"].shape == (5,) and space["goal"].shape == (2,)
    check_env(env, skip_render_check=True)
    env.close()


def test_without_a_lidar_or_with_scan_off_the_observation_stays_one_box():
    for env in (MobotEnv(), MobotEnv(args=LIDAR, scan=False)):
        assert isinstance(env.observation_space, spaces.Box) and env.observation_space.shape == (7,)
        obs, info = env.reset(seed=0)
        assert obs.shape == (7,) and "scan_t" not in info
        env.close()


def test_no_return_is_range_max_inside_the_box():
    env = MobotEnv(args=LIDAR, normalize=False)  # the empty world: no beam returns
    obs, _ = env.reset(seed=0)
    assert obs["scan"].dtype == np.float32 and (obs["scan"] == 12.0).all()
    assert env.observation_space.contains(obs)
    env.close()


def test_every_step_at_10_hz_sees_a_fresh_scan_of_the_walls(room):
    env = MobotEnv(room, pose=(0.5, -0.5, 0.0), goal=(2.0, -0.5), args=LIDAR, normalize=False)
    obs, info = env.reset(seed=4)
    assert info == {"t": 0.5, "scan_t": 0.5}
    scans, times = [obs["scan"]], []
    for _ in range(8):
        obs, reward, terminated, truncated, info = env.step(np.array([0.4, 0.0], dtype=np.float32))
        assert info["scan_t"] == info["t"]  # taken at the step the observation is
        scans.append(obs["scan"])
        times.append(info["t"])
    x = 0.5 + obs["odom"][0]
    env.close()
    assert times == pytest.approx([0.6, 0.7, 0.8, 0.9, 1.0, 1.1, 1.2, 1.3])
    ahead = [s[180] for s in scans]  # the beam nearest to straight ahead (+0.5 degree)
    assert ahead[0] == pytest.approx(HALF_X - 0.5, abs=NOISE)
    assert ahead[-1] == pytest.approx(HALF_X - x, abs=NOISE)
    assert all(b < a for a, b in zip(ahead[2:], ahead[3:]))  # driving at it: nearer every step
    assert scans[-1][90] == pytest.approx(HALF_Y - 0.5, abs=0.03)  # the right-hand wall (-89.5 degrees)


def test_reset_with_a_seed_replays_the_scan_noise_too(room):
    def episode(seed):
        env = MobotEnv(room, pose=(0.0, 0.0, 0.3), args=LIDAR, normalize=False)
        obs, _ = env.reset(seed=seed)
        trace = [obs["scan"]]
        for i in range(6):
            obs, *_ = env.step(np.array([0.3, 0.5 * math.sin(i)], dtype=np.float32))
            trace.append(np.concatenate([obs["odom"], obs["goal"], obs["scan"]]))
        env.close()
        return np.concatenate(trace)

    first = episode(9)
    assert np.array_equal(first, episode(9))
    assert not np.array_equal(first, episode(10))  # another seed, other noise


def test_the_observed_scan_is_the_run_folders_row(room, tmp_path):
    env = MobotEnv(room, pose=(-1.0, 0.5, 0.2), args=LIDAR, normalize=False, out=tmp_path / "runs")
    seen = {}
    obs, info = env.reset(seed=1)
    seen[info["t"]] = obs["scan"]
    for i in range(5):
        obs, _, _, _, info = env.step(np.array([0.3, 0.4], dtype=np.float32))
        seen[info["t"]] = obs["scan"]
    env.reset(seed=2)  # the first episode's folder is written; a second begins
    env.close()
    rows = np.load(tmp_path / "runs" / "episode_0000" / "sensors" / "robot" / "lidar.npy")
    assert (tmp_path / "runs" / "episode_0001" / "summary.json").is_file()
    for t, scan in seen.items():
        (row,) = rows[np.isclose(rows["t"], t)]
        assert np.array_equal(np.minimum(row["ranges"], np.float32(12.0)), scan), t
    assert len(seen) == 6 and list(rows["t"]) == pytest.approx([i / 10 for i in range(11)])  # 10 Hz from t = 0


def test_the_reward_sees_the_scan(room):
    env = MobotEnv(room, args=LIDAR, normalize=False, reward=lambda o: float(o.scan.min()),
                   terminated=lambda o: o.scan.min() < 0.4)
    env.reset(seed=0)
    _, reward, terminated, _, _ = env.step(np.array([0.0, 0.0], dtype=np.float32))
    env.close()
    assert reward == pytest.approx(HALF_Y, abs=0.04) and not terminated  # the nearest wall, 2 m to the side


def test_two_lidar_envs_in_an_async_vector_env(room):
    envs = gymnasium.vector.AsyncVectorEnv([lambda: MobotEnv(room, args=LIDAR, normalize=False) for _ in range(2)])
    try:
        obs, _ = envs.reset(seed=[3, 3])
        assert obs["scan"].shape == (2, 360) and np.array_equal(obs["scan"][0], obs["scan"][1])
        for _ in range(3):
            obs, rewards, terminated, truncated, info = envs.step(np.array([[0.4, 0.0], [0.0, 1.0]], dtype=np.float32))
        assert obs["odom"][0][0] > 0.05 and obs["odom"][1][2] > 0.2  # one drove, one turned
        assert obs["scan"][0][180] == pytest.approx(HALF_X - obs["odom"][0][0], abs=NOISE)
        assert not np.array_equal(obs["scan"][0], obs["scan"][1])
    finally:
        envs.close()
