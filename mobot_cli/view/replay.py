"""`mobot view RUN_DIR`: a run folder replayed in the page, with a timeline to play, pause, speed up and scrub.

One thread plays: it advances the time while playing and draws the robots at it; the slider sends
the user's scrubs back. A sweep folder offers its runs in a dropdown and switches between them.
"""

from __future__ import annotations

import threading
import time
from pathlib import Path
from typing import Any, Callable

import numpy as np

from mobot_cli.view import readings
from mobot_cli.view.movers import MoverShapes
from mobot_cli.view.panel import RobotList, Row, aim_camera, color_of, follow
from mobot_cli.view.paths import LIFT, draw_path, lighter, thin
from mobot_cli.view.robot import Robots
from mobot_cli.view.runfolder import RunView, read_run
from mobot_cli.view.world import draw_world

FRAME_S = 1 / 30  # the player's tick
SPEEDS = ("0.25", "0.5", "1", "2", "4", "10")


class Replay:
    """The page of one run folder (or of the chosen run of a sweep) and its player thread."""

    def __init__(self, server: Any, runs: list[Path], first: RunView,
                 on_notice: Callable[[str], None] = lambda _: None, robot_list: RobotList | None = None):
        self.server, self.runs, self.on_notice = server, runs, on_notice
        self.view: RunView | None = None
        self.models = Robots(server)
        self.mover_shapes = MoverShapes(server, list)
        self.t, self.playing = 0.0, False
        self._drawn: dict[tuple[str, str], int] = {}  # (robot, sensor) -> id of the cloud on the page
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._build_gui(robot_list)
        self.load(first)
        self._thread = threading.Thread(target=self._play, name="mobot-view-player", daemon=True)
        self._thread.start()

    def load(self, run: Path | RunView) -> RunView:
        """Show a run (a folder, or one already read) from its start (MobotError when it cannot be)."""
        view = run if isinstance(run, RunView) else read_run(run)
        for notice in view.notices:
            self.on_notice(notice)
        with self._lock:
            self._clear()
            self.view = view
            if view.plan is not None:
                mesh = draw_world(self.server, view.plan.world)
                aim_camera(self.server, mesh.lo, mesh.hi) if len(mesh.faces) else self._aim_at_paths()
            else:
                self._aim_at_paths()
            self._draw_robots(view)
            plans = [*view.plan.world.actors, *view.plan.movers] if view.plan is not None else []
            self.mover_shapes = MoverShapes(self.server, lambda: plans)
            self.slider.max = max(view.duration, 1e-3)
            self.slider.step = 1.0 / max(view.log_rate_hz, 1.0)
            self.t, self.playing = 0.0, False
            self.play.label = "Play"
            self._show(0.0)
        return view

    def close(self) -> None:
        """Stop the player thread."""
        self._stop.set()
        self._thread.join(timeout=2.0)

    # -- the page ---------------------------------------------------------------------------

    def _build_gui(self, robot_list: RobotList | None) -> None:
        gui = self.server.gui
        with gui.add_folder("Timeline"):
            if len(self.runs) > 1:
                self.run_pick = gui.add_dropdown("run", tuple(p.name for p in self.runs),
                                                 initial_value=self.runs[0].name)
                self.run_pick.on_update(self._pick_run)
            self.play = gui.add_button("Play")
            self.speed = gui.add_dropdown("speed", SPEEDS, initial_value="1")
            self.slider = gui.add_slider("t (s)", min=0.0, max=1.0, step=0.02, initial_value=0.0)
        self.play.on_click(lambda _: self._toggle())
        self.slider.on_update(self._scrub)
        # GUI elements are reused, never removed: viser would replay their updates to a page that
        # connects later, for elements it no longer has.
        note = "collisions: the run's total per robot (summary.json)"
        self.robot_list = robot_list or RobotList(self.server)
        self.robot_list.note = note

    def _toggle(self) -> None:
        with self._lock:
            if not self.playing and self.view is not None and self.t >= self.view.duration:
                self.t = 0.0  # play again from the start
            self.playing = not self.playing
            self.play.label = "Pause" if self.playing else "Play"

    def _scrub(self, event: Any) -> None:
        if event.client is None:  # our own update while playing
            return
        with self._lock:
            self.t = float(self.slider.value)
            self._show(self.t)

    def _pick_run(self, event: Any) -> None:
        folder = next(p for p in self.runs if p.name == self.run_pick.value)
        try:
            self.load(folder)
        except Exception as exc:  # noqa: BLE001 - a broken run of a sweep must not close the page
            self.on_notice(f"cannot show {folder}: {exc}")

    def _play(self) -> None:
        last = time.monotonic()
        while not self._stop.wait(FRAME_S):
            now = time.monotonic()
            with self._lock:
                if self.playing and self.view is not None:
                    self.t = min(self.t + (now - last) * float(self.speed.value), self.view.duration)
                    if self.t >= self.view.duration:
                        self.playing = False
                        self.play.label = "Play"
                    with self.server.atomic():  # one wake-up of viser's loop per frame
                        self.slider.value = round(self.t, 3)
                        self._show(self.t)
            last = now

    # -- drawing ----------------------------------------------------------------------------

    def _clear(self) -> None:
        for name in list(self.models.member):
            self.models.remove(name)
        self.models.flush()
        for node in ("/world", "/paths", "/readings", "/movers"):
            self.server.scene.remove_by_name(node)
        self._drawn = {}

    def _draw_robots(self, view: RunView) -> None:
        for i, track in enumerate(view.tracks):
            color = color_of(i)
            self.models.add(track.name, track.urdf)
            self.robot_list.colors[track.name] = color
            lifted = track.true[:, :3] + np.array([0.0, 0.0, LIFT])
            draw_path(self.server, f"/paths/{track.name}/true", thin(lifted), color)
            odom = np.column_stack([track.odom, lifted[:, 2]])
            draw_path(self.server, f"/paths/{track.name}/odom", thin(odom), lighter(color))
        self.robot_list.names([t.name for t in view.tracks])

    def _aim_at_paths(self) -> None:
        xy = np.concatenate([t.true[:, :2] for t in self.view.tracks]) if self.view else np.zeros((1, 2))
        aim_camera(self.server, (*xy.min(axis=0), 0.0), (*xy.max(axis=0), 0.0))

    def _show(self, t: float) -> None:
        """Draw every robot as it was at time ``t``."""
        rows = []
        for track in self.view.tracks:
            i = track.index(t)
            if i is None:
                self.models.hide(track.name)
                continue
            self.models.place(track.name, track.true[i].tolist(), track.joints.at(t) if track.joints else None)
            x, y, _, _, _, yaw = track.true[i].tolist()
            rows.append(Row(track.name, x, y, yaw, float(track.odom_error[i]), track.collisions,
                            *track.cmd[i].tolist()))
            if self.robot_list.follow.value and track.name == self.robot_list.selected:
                follow(self.server, x, y)
        self.models.selected = self.robot_list.selected
        self.models.flush()
        for track in self.view.tracks:
            if track.index(t) is not None:
                self._reading(track, t)
        self.robot_list.show(rows, force=not self.playing)
        if self.view.movers:
            self.mover_shapes.show(self.view.movers_at(t))

    def _reading(self, track: Any, t: float) -> None:
        if not track.readings:
            return
        times = [r[0] for r in track.readings]
        i = int(np.searchsorted(times, t, side="right")) - 1
        latest: dict[str, readings.Cloud] = {}
        for _, cloud in track.readings[max(0, i - 8):i + 1]:  # the latest of each sensor
            latest[cloud.sensor] = cloud
        for cloud in latest.values():
            if self._drawn.get((track.name, cloud.sensor)) == id(cloud):
                continue
            pose = self.models.link_pose(track.name, cloud.link)
            if pose is not None:
                self._drawn[(track.name, cloud.sensor)] = id(cloud)
                readings.draw(self.server, cloud, pose)
