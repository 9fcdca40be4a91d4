"""The page fed live from the timeline (`mobot run --view`, `mobot serve --view`).

``LiveView`` is a timeline consumer. On the simulation's thread it only files each record (the
latest state per robot, spawns and deletions in order, the latest reading per sensor): a dict
update, no drawing, never a wait. Its own thread draws what was filed at most ``rate_hz`` times a
second, and skips the drawing of poses while no browser is connected, so watching costs the
simulation little and not watching costs it nothing but the filing.
"""

from __future__ import annotations

import math
import threading
import time
from collections import deque
from typing import Any, Callable

from mobot_cli.common.transforms import Planar
from mobot_cli.plan import CAMERA_KINDS, Plan, RobotPlan
from mobot_cli.record.trajectory import odom_to_world
from mobot_cli.sim.state import RobotState
from mobot_cli.timeline.loop import Timeline
from mobot_cli.timeline.records import Deleted, Record, Sample, Spawned
from mobot_cli.view import readings
from mobot_cli.view.camera_panel import CameraFeed
from mobot_cli.view.movers import MoverShapes
from mobot_cli.view.panel import RobotList, Row, aim_camera, color_of, follow
from mobot_cli.view.paths import LivePath, lighter
from mobot_cli.view.robot import Robots, template_of
from mobot_cli.view.world import draw_world

DEFAULT_RATE_HZ = 20.0


class _Robot:
    """A robot's two paths and where its odometry starts."""

    def __init__(self, server: Any, plan: RobotPlan, color: tuple[int, int, int]):
        self.name = plan.name
        self.true = LivePath(server, f"/paths/{plan.name}/true", color)
        self.odom = LivePath(server, f"/paths/{plan.name}/odom", lighter(color))
        self.to_world: Planar | None = None  # its odom frame in the world, from its first state seen

    def remove(self, server: Any) -> None:
        server.scene.remove_by_name(f"/paths/{self.name}")
        server.scene.remove_by_name(f"/readings/{self.name}")


class LiveView:
    """Draws a running world's robots, paths and readings; attach it with ``watch(timeline)``."""

    def __init__(self, server: Any, plan: Plan, rate_hz: float = DEFAULT_RATE_HZ):
        self.server, self.plan, self.rate_hz = server, plan, rate_hz
        self.rate = plan.physics.rate_hz
        mesh = draw_world(server, plan.world)
        if len(mesh.faces):
            aim_camera(server, mesh.lo, mesh.hi)
        else:
            xy = [r.pose.xyz for r in plan.robots] or [(0.0, 0.0, 0.0)]
            aim_camera(server, tuple(min(p[i] for p in xy) for i in range(3)),
                       tuple(max(p[i] for p in xy) for i in range(3)))
        self.clock = server.gui.add_markdown("**t** = 0.000 s")
        self.robot_list = RobotList(server)
        self.robots: dict[str, _Robot] = {}
        self.models = Robots(server)
        self.camera = CameraFeed(server)  # the selected robot's camera in the panel
        for robot in plan.robots:  # load each URDF now, before the clock runs, not at its spawn
            template_of(robot.urdf)
        self.step = 0
        self.frames = 0  # pages drawn: for tests and the benchmark
        self.on_frame: Callable[[], None] | None = None  # called in each watched frame (serve: the pause state)
        self._latest: dict[str, RobotState] = {}
        self._movers: dict[str, tuple[float, float, float]] | None = None  # the movers' latest poses, when new
        self.mover_shapes = MoverShapes(server, list)  # watch() hands it the world's movers
        self._events: deque[tuple[str, Any]] = deque()
        self._readings: dict[tuple[str, str], Any] = {}
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="mobot-view-live", daemon=True)
        self._thread.start()

    def watch(self, timeline: Timeline) -> None:
        """Attach to a timeline, taking in the robots already in its world."""
        for robot in timeline.robots.values():
            self._events.append(("spawned", robot))
        self.mover_shapes.plans = timeline.world.mover_plans
        timeline.attach(self)

    def __call__(self, record: Record) -> None:
        """File one record (the Consumer interface; runs on the simulation's thread)."""
        if isinstance(record, Sample):
            with self._lock:
                self._latest.update(record.states)
                self.step = record.step
                if record.movers is not None:
                    self._movers = record.movers
        elif isinstance(record, Spawned):
            self._events.append(("spawned", record.robot))
        elif isinstance(record, Deleted):
            self._events.append(("deleted", record.name))
        else:
            robot, sensor = getattr(record, "robot", None), getattr(record, "sensor", None)
            if getattr(sensor, "kind", None) in CAMERA_KINDS:
                self.camera.take(record, self.robot_list.selected)
            elif isinstance(robot, str) and sensor is not None:
                with self._lock:
                    self._readings[(robot, getattr(sensor, "name", str(sensor)))] = record

    def close(self) -> None:
        """Draw the last states and stop the thread (once: the scene may be reset afterwards)."""
        if self._stop.is_set():
            return
        self._stop.set()
        self._thread.join(timeout=5.0)
        self.draw(force=True)

    def _run(self) -> None:
        period = 1.0 / self.rate_hz
        next_at = time.monotonic()
        while not self._stop.is_set():
            next_at += period
            try:
                self.draw()
            except Exception:  # noqa: BLE001 - a drawing bug must not end the view, nor the run
                pass
            wait = next_at - time.monotonic()
            if wait < 0:  # too slow for the rate: skip frames rather than fall behind
                next_at, wait = time.monotonic(), 0.0
            self._stop.wait(wait)

    def draw(self, force: bool = False) -> None:
        """Draw what was filed since the last frame, as one batch of messages."""
        # atomic(): viser wakes its event loop once per batch instead of once per message, and
        # each wake-up costs this thread a round trip for the GIL while the simulation runs.
        with self.server.atomic():
            self._draw(force)
        self.frames += 1

    def _draw(self, force: bool) -> None:
        while self._events:
            kind, what = self._events.popleft()
            if kind == "spawned" and what.name not in self.robots:
                self.robots[what.name] = _Robot(self.server, what, color_of(len(self.robot_list.colors)))
                self.robot_list.colors[what.name] = color_of(len(self.robot_list.colors))
                self.models.add(what.name, what.urdf)
            elif kind == "deleted" and what in self.robots:
                self.robots.pop(what).remove(self.server)
                self.models.remove(what)
                with self._lock:
                    self._latest.pop(what, None)
            self.robot_list.names(list(self.robots))
        with self._lock:
            latest, step = dict(self._latest), self.step
            movers, self._movers = self._movers, None
        watched = force or bool(self.server.get_clients())
        rows = [self._robot(name, state, watched) for name, state in latest.items() if name in self.robots]
        if watched:
            self.models.selected = self.robot_list.selected
            self.models.flush()
            self.clock.content = f"**t** = {step / self.rate:.3f} s"
            if self.on_frame is not None:
                self.on_frame()
            self.robot_list.show(rows, force=force)
            self._draw_readings()
            self.camera.draw()
            if movers is not None:
                self.mover_shapes.show(movers)

    def _robot(self, name: str, state: RobotState, watched: bool) -> Row:
        robot = self.robots[name]
        robot.to_world = robot.to_world or odom_to_world(state)
        x, y = robot.to_world(state.odom_x, state.odom_y)
        error = math.hypot(x - state.true_x, y - state.true_y)
        robot.true.add(state.true_x, state.true_y, state.true_z)
        robot.odom.add(x, y, state.true_z)
        if watched:
            self.models.place(name, (state.true_x, state.true_y, state.true_z, state.true_roll, state.true_pitch,
                                     state.true_yaw), state.joint_positions)
            robot.true.flush()
            robot.odom.flush()
            if self.robot_list.follow.value and name == self.robot_list.selected:
                follow(self.server, state.true_x, state.true_y)
        return Row(name, state.true_x, state.true_y, state.true_yaw, error, state.collisions,
                   state.cmd_linear, state.cmd_angular)

    def _draw_readings(self) -> None:
        with self._lock:
            pending, self._readings = self._readings, {}
        for record in pending.values():
            cloud = readings.cloud_of(record)
            pose = self.models.link_pose(cloud.robot, cloud.link) if cloud is not None else None
            if pose is not None:
                readings.draw(self.server, cloud, pose)

