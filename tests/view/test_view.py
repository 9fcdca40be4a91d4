"""The view without a browser: the optional extra, run folders read back, robots' kinematics,
sensor readings (the hook), the pause/step gate in a real live server, and the import rules."""

from __future__ import annotations

import ast
import dataclasses
import json
import shutil
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from mobot_cli.cli import invoke
from mobot_cli.scenario.prepare import prepare

REPO = Path(__file__).resolve().parents[2]
viser = pytest.importorskip("viser", reason="the view extra (viser) is not installed")


@pytest.fixture(scope="module")
def fleet_run(tmp_path_factory) -> Path:
    """The bundled fleet scenario (five robots, CSV and bag), run once."""
    out = tmp_path_factory.mktemp("view") / "fleet"
    assert invoke(["run", REPO / "scenarios" / "fleet.yaml", "--out", out, "--quiet"]).exit_code == 0
    return out


@pytest.fixture
def page():
    from mobot_cli.view.page import close_page, open_page

    server = open_page(0)
    yield server
    close_page(server)


def test_without_the_extra_mobot_view_says_how_to_install_it(monkeypatch, fleet_run):
    monkeypatch.setitem(sys.modules, "viser", None)  # what `import viser` meets without the extra
    for args in (["view", fleet_run], ["run", REPO / "scenarios" / "quickstart.yaml", "--view"],
                 ["serve", "--view"]):
        outcome = invoke(args)
        assert (outcome.exit_code, outcome.stdout) == (2, "")
        assert outcome.stderr == ("mobot: error: the 3D view needs viser, which is not installed. Install the view "
                                  "extra: pip install 'mobot-cli[view]' (it brings viser, whose web page ships "
                                  "inside the wheel and works offline).\n")


def test_a_folder_without_a_run_is_bad_input(tmp_path):
    outcome = invoke(["view", tmp_path])
    assert outcome.exit_code == 2
    assert outcome.stderr == (f"mobot: error: '{tmp_path}' is neither a run folder nor a sweep folder with runs. "
                              "Give the folder that mobot run --out, mobot serve --out or mobot sweep --out "
                              "wrote.\n")


def test_a_run_folder_reads_back_with_paths_joints_and_the_record(fleet_run):
    from mobot_cli.view.runfolder import read_run

    view = read_run(fleet_run)
    summary = json.loads((fleet_run / "summary.json").read_text())
    assert [t.name for t in view.tracks] == [f"mobot_{i}" for i in range(5)]
    assert view.duration == pytest.approx(6.0) and view.log_rate_hz == 48
    assert len(view.plan.world.bodies) == 0 and view.plan.world.ground_plane
    for track in view.tracks:
        robot = summary["robots"][track.name]
        assert track.true[-1, :2] == pytest.approx([robot["final_pose"]["x"], robot["final_pose"]["y"]], abs=1e-6)
        assert track.odom_error[-1] == pytest.approx(robot["odom_error"]["position"], abs=2e-6)
        assert track.collisions == robot["collisions"] and "<robot" in track.urdf
        # Wheels turn forward while the robot drives: joint_states from the bag, every log row.
        assert track.joints.names == ["left_wheel_joint", "right_wheel_joint"]
        assert len(track.joints.t) == len(track.t) == 289
        start, end = track.joints.at(0.9), track.joints.at(6.0)
        assert end["right_wheel_joint"] - start["right_wheel_joint"] > 10.0  # rad: over 0.5 m on r = 5 cm
        assert track.index(-0.1) is None and track.index(3.0) == 144


def test_a_sweep_folder_offers_its_runs(tmp_path):
    from mobot_cli.view.runfolder import runs_of

    out = tmp_path / "sweep"
    assert invoke(["sweep", REPO / "scenarios" / "quickstart.yaml", "--grid", "seed=1,2", "--set", "duration=1",
                   "--out", out, "--jobs", "1", "--quiet"]).exit_code == 0
    assert [p.name for p in runs_of(out)] == ["0000", "0001"]


def test_robots_are_posed_with_their_joints_as_yourdfpy_poses_them(page):
    """Forward kinematics of the batched drawing against yourdfpy's own, for a wheel turned 0.7 rad."""
    import io

    import yourdfpy

    from mobot_cli.view.robot import Robots

    urdf = prepare(REPO / "scenarios" / "quickstart.yaml").plan.robots[0].urdf
    robots = Robots(page)
    robots.add("a", urdf)
    robots.add("b", urdf)
    pose = (1.0, -2.0, 0.1, 0.05, -0.1, 2.0)
    robots.place("a", pose, {"left_wheel_joint": 0.7, "right_wheel_joint": -0.3})
    robots.flush()
    model = yourdfpy.URDF.load(io.StringIO(urdf), load_meshes=False, build_scene_graph=True)
    model.update_cfg({"left_wheel_joint": 0.7, "right_wheel_joint": -0.3})
    root = np.eye(4)
    from mobot_cli.view.geometry import rpy_matrices

    root[:3, :3], root[:3, 3] = rpy_matrices(np.array([pose[3:]]))[0], pose[:3]
    for link in ("left_wheel", "right_wheel", "base_link"):
        expected = root @ model.get_transform(link, model.base_link)
        assert robots.link_pose("a", link) == pytest.approx(expected, abs=1e-9)
    # "b" was never placed: it stays hidden (scale 0), and one node per link mesh serves both.
    handles = robots.groups[urdf].handles
    assert len(handles) == len(robots.groups[urdf].template.meshes)
    assert [list(h.batched_scales) for h in handles] == [[1.0, 0.0]] * len(handles)
    robots.remove("a")
    robots.flush()
    assert robots.groups[urdf].names == ["b"]


@dataclasses.dataclass(frozen=True)
class Reading:
    """What a sensors record may look like: the view's hook reads robot, sensor and ranges."""

    step: int
    robot: str
    sensor: object
    ranges: np.ndarray


def lidar(samples: int = 4):
    from mobot_cli.plan import RayAxis, SensorSpec

    return SensorSpec(name="scan", kind="lidar", link="base_link", every=24, xyz=(0.1, 0.0, 0.2),
                      horizontal=RayAxis(samples, -np.pi / 2, np.pi / 2), range_min=0.1, range_max=5.0)


def test_a_lidar_reading_becomes_points_on_its_link():
    from mobot_cli.view.readings import cloud_of

    cloud = cloud_of(Reading(0, "mobot", lidar(), np.array([1.0, 2.0, np.inf, 0.05])))
    # -90 deg: 1 m to the right; -30 deg: 2 m; inf and below range_min are no hits; offset by the mount.
    assert (cloud.robot, cloud.sensor, cloud.link) == ("mobot", "scan", "base_link")
    assert cloud.points == pytest.approx(np.array([[0.1, -1.0, 0.2], [0.1 + 2 * np.cos(np.pi / 6), -1.0, 0.2]]),
                                         abs=1e-6)
    assert cloud_of(Reading(0, "mobot", "not a spec", np.ones(4))) is None


def test_the_live_view_draws_states_and_readings_on_the_page(page):
    """A LiveView on a real timeline: robots appear, move, and a reading record is drawn."""
    from mobot_cli.sim.bullet.world import World
    from mobot_cli.timeline.loop import Timeline
    from mobot_cli.view.live import LiveView

    plan = prepare(REPO / "scenarios" / "fleet.yaml").plan
    live = LiveView(page, plan, rate_hz=50)
    try:
        with World(plan.physics, plan.world, seed=plan.seed) as world:
            timeline = Timeline(plan, world)
            timeline.attach(lambda record: None)
            timeline.start()  # spawned before the view attaches: watch() takes them in
            live.watch(timeline)
            for _ in range(480):
                timeline.tick()
                timeline.advance()
            live(Reading(timeline.step, "mobot_2", lidar(), np.array([1.0, 1.0, 1.0, 1.0])))
            frames = []
            live.on_frame = lambda: frames.append(live.clock.content)  # serve --view shows its pause state here
            live.draw(force=True)
            assert frames == [live.clock.content] and frames[0].startswith("**t** = 1.9")  # after the clock
        assert sorted(live.robots) == [f"mobot_{i}" for i in range(5)]
        pose = live.models.link_pose("mobot_2", "base_link")
        assert pose[:2, 3] == pytest.approx([world_x := 2.0 + 0.2 * 1.5, 0.0], abs=0.15), world_x
        assert "mobot_2" in live.robot_list._text and "0.20, 0.20" in live.robot_list._text
        path = live.robots["mobot_2"].true.points  # a point per frame drawn, 5 cm apart at least
        assert len(path) >= 2 and np.hypot(*(np.array(path[-1][:2]) - pose[:2, 3])) < 0.05
        assert "/readings/mobot_2/scan" in page.scene._handle_from_node_name
    finally:
        live.close()


def test_the_page_buttons_press_the_servers_own_pause_state():
    """The page's World buttons press LiveServer.control, the state the protocol's pause/step use."""
    import tempfile

    from mobot_cli.live.client import Client
    from mobot_cli.live.server import LiveServer
    from mobot_cli.scenario.prepare import prepare_target
    from mobot_cli.view.controls import GateControl

    ready = threading.Event()
    folder = Path(tempfile.mkdtemp(prefix="mobot-t-"))  # a socket path must stay short
    endpoint = f"ipc://{folder}/s.sock"
    server = LiveServer(prepare_target("empty").plan, endpoint, rtf=None)
    gate = GateControl(server.control, lambda *a: None)  # what the page's buttons call
    thread = threading.Thread(target=server.serve, args=(lambda where: ready.set(),), daemon=True)
    thread.start()
    assert ready.wait(60)
    with Client(endpoint, timeout=10) as client:
        client.ping()
        gate.pause()
        time.sleep(0.1)
        held = client.ping()["step"]
        time.sleep(0.2)
        assert client.ping()["step"] == held  # paused, yet answering
        assert client.ping()["state"] == "paused" and client.call("pause")["changed"] is False
        gate.step(5)
        deadline = time.monotonic() + 60  # only catches steps that never come, busy machine or not
        while client.ping()["step"] < held + 5 and time.monotonic() < deadline:
            time.sleep(0.01)
        time.sleep(0.1)
        assert client.ping()["step"] == held + 5
        assert client.request("step", steps=3)["step"] == held + 8  # the protocol's step, on the same state
        client.request("resume")
        assert not gate.paused  # the page sees what the protocol did
        deadline = time.monotonic() + 60  # running again: steps come, however slowly
        while client.ping()["step"] <= held + 50 and time.monotonic() < deadline:
            time.sleep(0.01)
        assert client.ping()["step"] > held + 50
        client.stop()
    thread.join(timeout=10)
    shutil.rmtree(folder, ignore_errors=True)


# What the view may import of mobot: the run door and every layer below the doors (tests/test_layers.py).
LAYERS = {"view": {"view", "run", "record", "ros", "timeline", "scenario", "assets", "sim", "common", "errors", "plan"}}


def test_the_view_imports_only_the_layers_below_it_and_nothing_below_imports_the_view():
    """DESIGN: cli -> (run, live, sweep, view) -> record -> ... -> sim; viser only in view/."""
    package = REPO / "mobot_cli"
    for path in package.rglob("*.py"):
        layer = path.relative_to(package).parts[0]
        for node in ast.walk(ast.parse(path.read_text())):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                     else [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            for name in names:
                parts = name.split(".")
                if parts[0] == "viser":
                    assert layer == "view", f"{path} imports viser"
                if parts[0] != "mobot_cli" or len(parts) < 2:
                    continue
                if layer == "view":
                    assert parts[1] in LAYERS["view"], f"{path} imports {name}"
                elif layer != "cli":
                    assert parts[1] != "view", f"{path} imports {name}: only the CLI may use the view"


def test_mobot_run_without_view_imports_no_view_code(tmp_path):
    import subprocess

    code = ("import sys; from mobot_cli.cli import invoke; "
            f"o = invoke(['run', {str(REPO / 'scenarios' / 'quickstart.yaml')!r}, '--out', {str(tmp_path / 'r')!r}, "
            "'--quiet', '--duration', '1']); "
            "print(o.exit_code, sorted(m for m in ('viser', 'websockets', 'mobot_cli.view') if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.stdout.strip() == "0 []", done.stderr


def test_paths_keep_a_point_every_five_centimetres_and_both_ends():
    from mobot_cli.view.paths import thin

    line = np.column_stack([np.linspace(0.0, 1.0, 101), np.zeros(101), np.zeros(101)])  # 1 cm apart
    x = thin(line)[:, 0]
    gaps = np.diff(x)[:-1]  # the last gap ends at the kept end point
    assert (x[0], x[-1]) == (0.0, 1.0) and len(x) in (18, 19, 20, 21)
    assert gaps.min() >= 0.05 - 1e-9 and gaps.max() <= 0.06 + 1e-9


def test_a_replay_switches_between_the_runs_of_a_sweep(page, fleet_run, tmp_path):
    from mobot_cli.view.replay import Replay
    from mobot_cli.view.runfolder import read_run

    other = tmp_path / "quick"
    assert invoke(["run", REPO / "scenarios" / "quickstart.yaml", "--out", other, "--quiet", "--duration", "2"]
                  ).exit_code == 0
    replay = Replay(page, [fleet_run, other], read_run(fleet_run))
    try:
        assert sorted(replay.models.member) == [f"mobot_{i}" for i in range(5)]
        replay.run_pick.value = "quick"  # what the page's dropdown does
        assert sorted(replay.models.member) == ["mobot"] and replay.slider.max == pytest.approx(2.0)
        replay.slider.value = 1.0
        replay._scrub(type("Event", (), {"client": object()})())  # a user's scrub, as the page sends it
        assert replay.t == 1.0 and "mobot" in replay.robot_list._text
    finally:
        replay.close()
