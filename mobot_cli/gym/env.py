"""A Gymnasium environment on mobot's timeline: one robot, a twist as the action.

Observation: the robot's odometry ``[x, y, yaw, vx, wz]`` in its odom frame (its spawn pose)
and the goal in that frame ``[gx, gy]``, one flat Box of 7; for a robot with a lidar, a Dict
``{"odom": Box(5), "goal": Box(2), "scan": Box(beams, 0, range_max)}`` whose scan is the
lidar's latest reading with no return (+inf) as ``range_max``. Action: ``[linear, angular]``
(m/s, rad/s), held for one control period (``physics rate / control_hz`` whole steps);
``holonomic=True`` makes it ``[linear, angular, linear_y]`` for a mecanum or omni robot (the
sideways speed scaled, and bounded, as ``linear``; other robots are refused).

``normalize=True`` (the default) puts both in the ranges learning libraries assume (Stable-
Baselines3 warns otherwise, and PPO with its defaults learns nothing from raw m/s): the action
is in [-1, 1], scaled to ``max_linear`` and ``max_angular``; positions and the goal are divided
by the goal's distance from the spawn pose (at least 1 m), yaw by pi, speeds by the maximum
speeds, ranges by the lidar's ``range_max``. ``normalize=False`` keeps SI units. Reward
and termination are yours to give (callables of a ``StepOutcome``); by default the reward is
minus the distance to the goal per control period, and an episode ends when the robot is
within ``goal_tolerance``. ``camera=True`` (or a camera's name) adds the robot's camera to the
Dict: ``"image"`` uint8 (H, W, 3), or (H, W, 1) for mono8, as Stable-Baselines3's CnnPolicy and
MultiInputPolicy take images, and for a depth camera ``"depth"`` float32 (H, W, 1) with nothing
within the far clip as the far clip (divided by it when normalized); the camera renders only
at its own rate (docs/cameras.md). Every ``reset`` builds the world afresh, so ``reset(seed=s)``
always starts the same episode, the lidar's noise included; without ``out`` it does so from
what the first reset made and kept: the scenario prepared (only its seed changes), the robot
resolved, and the PyBullet client with the world's static bodies (sim/bullet/clients.py) and
the robot's body, restored as just loaded (sim/bullet/kept_body.py), and on PyBullet the end of
the first settle, put back instead of stepping when nothing in it depends on the seed
(sim/bullet/settled.py), so an episode is byte for byte the one a build from nothing gives
(tests/run/test_scale_golden.py, tests/gym/test_resets.py, tests/gym/test_settled.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Callable, Optional

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from mobot_cli.api import RobotState, Scan, Simulation, Status
from mobot_cli.api.cameras import pick_camera
from mobot_cli.api.numbers import bounded
from mobot_cli.api.sensors import pick, robot_plan
from mobot_cli.errors import SimulationFault, UsageError
from mobot_cli.gym.camera import camera_observation, camera_space
from mobot_cli.scenario.limits import (
    MAX_ANGULAR_SPEED,
    MAX_COORDINATE,
    MAX_RATE_HZ,
    MAX_SECONDS,
    MAX_SPEED,
)
from mobot_cli.scenario.prepare import Prepared, prepare_target
from mobot_cli.sim.bullet.clients import keep_at_least
from mobot_cli.sim.bullet.kept_body import keeping_robot_bodies
from mobot_cli.sim.holonomic import KINDS as HOLONOMIC


@dataclass(frozen=True)
class StepOutcome:
    """What the reward and termination callables see after a control period."""

    state: RobotState  # odometry and ground truth (see RobotState)
    goal: tuple[float, float]  # in the robot's odom frame
    action: tuple[float, ...]  # (linear, angular), and linear_y for a holonomic env
    steps: int  # control periods since reset
    scan: Optional[np.ndarray] = None  # the observation's scan (finite), None without a lidar

    @property
    def distance(self) -> float:
        """Distance from the robot's odometry to the goal (m)."""
        return math.hypot(self.goal[0] - self.state.odom_x, self.goal[1] - self.state.odom_y)


Reward = Callable[[StepOutcome], float]
Termination = Callable[[StepOutcome], bool]


class MobotEnv(gym.Env):
    """Drive one robot of a mobot world toward a goal (or whatever your reward says)."""

    metadata = {"render_modes": []}

    def __init__(self, world: str | Path = "empty", description: str = "mobot", *, robot: str = "robot",
                 pose: tuple[float, float, float] = (0.0, 0.0, 0.0), goal: tuple[float, float] = (2.0, 0.0),
                 goal_tolerance: float = 0.1, control_hz: float = 10.0, max_linear: float = 0.5,
                 max_angular: float = 2.0, settle: float = 0.5, reward: Optional[Reward] = None,
                 terminated: Optional[Termination] = None, args: Optional[dict[str, str]] = None,
                 scan: bool = True, scan_sensor: Optional[str] = None, out: str | Path | None = None,
                 normalize: bool = True, holonomic: bool = False, camera: bool | str = False):
        self.world, self.description, self.robot = str(world), description, robot
        self.holonomic = holonomic
        # Every number checked here, before a world exists (docs/errors.md "Limits").
        pose = tuple(bounded(f"pose[{i}]", v, "m" if i < 2 else "rad", MAX_COORDINATE) for i, v in enumerate(pose))
        goal = tuple(bounded(f"goal[{i}]", v, "m", MAX_COORDINATE) for i, v in enumerate(goal))
        goal_tolerance = bounded("goal_tolerance", goal_tolerance, "m", MAX_COORDINATE, low=0.0, strict=True)
        control_hz = bounded("control_hz", control_hz, "Hz", MAX_RATE_HZ, low=0.0, strict=True)
        max_linear = bounded("max_linear", max_linear, "m/s", MAX_SPEED, low=0.0, strict=True)
        max_angular = bounded("max_angular", max_angular, "rad/s", MAX_ANGULAR_SPEED, low=0.0, strict=True)
        settle = bounded("settle", settle, "s", MAX_SECONDS, low=0.0)
        self.pose, self.goal = pose, (goal[0], goal[1])
        self.goal_tolerance, self.control_hz, self.settle = goal_tolerance, control_hz, settle
        self.reward_fn = reward or (lambda o: -o.distance)
        self.terminated_fn = terminated or (lambda o: o.distance < self.goal_tolerance)
        self.args = dict(args or {})
        self.out = None if out is None else Path(out)  # episode k's run folder: out/episode_000k
        plan = robot_plan(self.robot, self.description, args=self.args) if scan or holonomic or camera else None
        if holonomic and (plan.drive is None or plan.drive.kind not in HOLONOMIC):
            kind = f"a {plan.drive.kind} drive" if plan.drive is not None else "no drive"
            raise UsageError(f"holonomic=True: robot '{self.robot}' ({self.description}) has {kind}",
                             hint="Only mecanum and omni bases take linear_y; leave holonomic off.")
        self._lidar = self._find_lidar(plan.sensors, scan_sensor) if scan else None
        high = np.array([max_linear, max_angular] + ([max_linear] if holonomic else []), dtype=np.float32)
        self.normalize = normalize
        self._goal = self._goal_in_odom()
        # Observations are divided by these (all ones in SI units): x, y, yaw, vx, wz, gx, gy.
        length = max(math.hypot(*self._goal), 1.0)
        self._scale = (np.array([length, length, np.pi, max_linear, max_angular, length, length], np.float32)
                       if normalize else np.ones(7, np.float32))
        unit = np.ones(len(high), np.float32)
        self.action_space = spaces.Box(-unit if normalize else -high, unit if normalize else high, dtype=np.float32)
        # Odometry is bounded by the farthest spawn a scenario allows and by what a robot can do.
        far, turn = 2e6, np.float32(np.pi)
        odom = np.array([far, far, turn, 1e3, 1e3], dtype=np.float32) / self._scale[:5]
        goal = np.array([far, far], dtype=np.float32) / self._scale[5:]
        if self._lidar is None:
            bound = np.concatenate([odom, goal])
            self.observation_space = spaces.Box(-bound, bound, dtype=np.float32)
        else:
            rows = self._lidar.vertical.samples if self._lidar.vertical is not None else 1
            beams = self._lidar.horizontal.samples if self._lidar.horizontal is not None else 1
            self._range_max = np.float32(self._lidar.range_max)
            top = np.float32(1.0) if normalize else self._range_max
            self.observation_space = spaces.Dict({
                "odom": spaces.Box(-odom, odom, dtype=np.float32),
                "goal": spaces.Box(-goal, goal, dtype=np.float32),
                "scan": spaces.Box(0.0, top, (beams,) if rows <= 1 else (rows, beams), np.float32)})
        self._camera = None
        if camera:
            self._camera = pick_camera(self.robot, plan.sensors, camera if isinstance(camera, str) else None)
            self.observation_space = camera_space(self.observation_space, self._camera, normalize, odom, goal)
        self._low, self._high = tuple(float(v) for v in -high), tuple(float(v) for v in high)
        self._sim: Simulation | None = None
        self._steps_per_action = 0
        self._count = 0
        self._episodes = 0
        self._kept: dict[str, Any] = {}  # what resets reuse: see _open and _robot_plan

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        """A fresh world at t = 0 with the robot at its pose, settled; ``seed`` seeds the world."""
        super().reset(seed=seed)
        world_seed = int(self.np_random.integers(0, 2**31 - 1))
        out = None if self.out is None else self.out / f"episode_{self._episodes:04d}"
        self._episodes += 1
        # The robot's body stays in the kept client from one reset to the next (sim/bullet/kept_body.py);
        # only here: a world closed anywhere else (env.close()) takes its body out.
        with keeping_robot_bodies(out is None):
            self._close_sim()
            self._sim = self._open(world_seed, out)
            self._start()
        self._count = 0
        self._goal = self._goal_in_odom()
        scan = self._scan()
        return self._observation(self._sim.state(self.robot), scan), self._info(scan)

    def _start(self) -> None:
        """The robot spawned in the new world and settled."""
        rate = self._sim.rate_hz
        steps = rate / self.control_hz
        if abs(steps - round(steps)) > 1e-9 or round(steps) < 1:
            raise UsageError(f"control_hz {self.control_hz:g} is not a whole number of physics steps at {rate} Hz",
                             hint=f"Pick a divisor of {rate}, e.g. 10 at 240 Hz.")
        self._steps_per_action = round(steps)
        self._sim.spawn_plan(self._robot_plan(rate))
        self._sim.settle(self.settle)  # the kept end of the same settle, when there is one

    def _observation(self, s: RobotState, scan: Scan | None):
        obs = self._base_observation(s, scan)
        if self._camera is None:
            return obs
        return camera_observation(obs, self._sim.image(self.robot, self._camera.name), self._camera, self.normalize)

    def _open(self, world_seed: int, out: Path | None) -> Simulation:
        """The world at t = 0 with ``world_seed``: prepared once (the seed is the only thing that
        differs between resets), built in a kept PyBullet client that holds its static bodies.
        With ``out`` (a run folder per episode, whose scenario.yaml names the seed) it is prepared
        each time."""
        if out is not None:
            return Simulation.open(self.world, seed=world_seed, out=out)
        key = (self.world, Path.cwd())
        if self._kept.get("world") != key:
            self._kept.update(world=key, prepared=prepare_target(self.world, [f"seed={world_seed}"]))
            keep_at_least(1)
        prepared: Prepared = self._kept["prepared"]
        return Simulation(Prepared(prepared.scenario, replace(prepared.plan, seed=world_seed), prepared.resolved_yaml))

    def _robot_plan(self, rate: int):
        """The robot resolved as Simulation.spawn resolves it, once for its settings."""
        key = (self.robot, self.description, tuple(self.pose), tuple(sorted(self.args.items())), rate, Path.cwd())
        if self._kept.get("robot") != key:
            x, y, yaw = self.pose
            plan = robot_plan(self.robot, self.description, rate_hz=rate, x=x, y=y, yaw=yaw, args=self.args,
                              base_dir=Path.cwd())
            self._kept.update(robot=key, robot_plan=plan)
        return self._kept["robot_plan"]

    def step(self, action):
        """Hold ``action`` for one control period."""
        if self._sim is None:
            raise UsageError("call reset() before step()")
        action = self._action(action)
        if self.normalize:  # [-1, 1] to the robot's limits
            action = [min(max(float(v), -1.0), 1.0) * hi for v, hi in zip(action, self._high)]
        clipped = tuple(min(max(float(v), lo), hi) for v, lo, hi in zip(action, self._low, self._high))
        linear, angular = clipped[:2]
        self._sim.command(self.robot, linear, angular, linear_y=clipped[2] if self.holonomic else 0.0)
        fault = None
        try:
            self._sim.step(self._steps_per_action)
        except SimulationFault as exc:  # it tipped over, flew, ran away: the episode ends here
            fault = exc
        self._count += 1
        state, scan = self._sim.state(self.robot), self._scan()
        obs = self._observation(state, scan)
        scan_m = self._finite(scan) if self._lidar else None
        outcome = StepOutcome(state, self._goal, clipped, self._count, scan_m)
        reward = float(self.reward_fn(outcome))
        info = self._info(scan)
        if fault is None:
            return obs, reward, bool(self.terminated_fn(outcome)), False, info
        info["fault"] = {"robot": fault.robot, "step": fault.step, "kind": fault.kind, "message": str(fault)}
        self._sim.close(Status.FAULT, str(fault), fault=fault)
        self._sim = None  # reset() next
        return obs, reward, True, False, info

    def close(self) -> None:
        self._close_sim()

    def _action(self, action) -> list[float]:
        """Two (three when holonomic) finite numbers, or a UsageError before the world is touched
        (NaN would not clip)."""
        shape = "[linear, angular, linear_y]" if self.holonomic else "[linear, angular]"
        try:
            values = np.asarray(action, dtype=np.float64).reshape(-1).tolist()
        except (TypeError, ValueError):
            raise UsageError(f"step: the action must be {shape} numbers, got {action!r:.60}") from None
        if len(values) != len(self._high):
            raise UsageError(f"step: the action must be {shape}, got {len(values)} numbers")
        if not all(math.isfinite(v) for v in values):
            raise UsageError(f"step: the action {values} holds a number that is not finite")
        return values

    def _goal_in_odom(self) -> tuple[float, float]:
        """The goal (world frame) in the robot's odom frame, whose origin is its spawn pose."""
        x0, y0, yaw0 = self.pose
        dx, dy = self.goal[0] - x0, self.goal[1] - y0
        c, s = math.cos(yaw0), math.sin(yaw0)
        return c * dx + s * dy, -s * dx + c * dy

    def _find_lidar(self, sensors, sensor: Optional[str]):
        """The lidar whose scan is observed (None: the robot has none), among the robot's sensors."""
        if sensor is None and not any(spec.kind == "lidar" for spec in sensors):
            return None
        return pick(self.robot, sensors, sensor, "lidar")

    def _scan(self) -> Scan | None:
        return None if self._lidar is None else self._sim.scan(self.robot, self._lidar.name)

    def _finite(self, scan: Scan | None) -> np.ndarray:
        """The ranges in the observation: no return as range_max (a full-range scan before the first)."""
        if scan is None:
            return np.full(self.observation_space["scan"].shape, self._range_max, np.float32)
        return np.minimum(scan.ranges, self._range_max).astype(np.float32)

    def _base_observation(self, s: RobotState, scan: Scan | None):
        gx, gy = self._goal
        flat = np.array([s.odom_x, s.odom_y, s.odom_yaw, s.odom_vx, s.odom_wz, gx, gy], dtype=np.float32) / self._scale
        if self._lidar is None:
            return flat
        ranges = self._finite(scan)
        return {"odom": flat[:5], "goal": flat[5:],
                "scan": ranges / self._range_max if self.normalize else ranges}

    def _info(self, scan: Scan | None) -> dict[str, Any]:
        """The time now, and when the observed scan was taken (the sensor runs at its own rate)."""
        info: dict[str, Any] = {"t": self._sim.t}
        if self._lidar is not None:
            info["scan_t"] = None if scan is None else scan.t
        return info

    def _close_sim(self) -> None:
        if self._sim is not None:
            self._sim.close()
            self._sim = None
