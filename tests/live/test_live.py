"""`mobot serve` as a real process, driven through the real CLI: spawn, delete, list, cmd, odom."""

from __future__ import annotations

import json
import math
import subprocess
import sys
import time
from pathlib import Path

import pytest

from mobot_cli.cli import invoke
from tests.live.live_server import REPO, LiveProcess

BAD_ROBOTS = REPO / "tests" / "bad" / "robots"
TUTORIAL = [(0.0, 0.0), (1.0, 1.0), (2.0, 0.0), (1.0, 2.0), (0.0, 2.0)]


@pytest.fixture(scope="module")
def live(tmp_path_factory):
    server = LiveProcess("--fast", cache_dir=tmp_path_factory.getbasetemp() / "mobot-cache")
    yield server
    server.kill()


@pytest.fixture(scope="module")
def blocker(live):
    """A robot at (20, 20) for tests that need one in the way, whichever tests ran before."""
    with live.client() as client:
        client.spawn("blocker", description="mobot", pose={"x": 20.0, "y": 20.0})
    return "blocker"


@pytest.fixture
def mobot(live):
    """Run one CLI command against the live server: (exit code, stdout, stderr)."""

    def run(*args: str) -> tuple[int, str, str]:
        done = invoke([*args, "--endpoint", live.endpoint])
        assert "Traceback" not in done.stderr
        return done.exit_code, done.stdout, done.stderr

    return run


def spawn_json(mobot, *args: str) -> dict:
    code, out, err = mobot("spawn", *args, "--json")
    assert code == 0, err
    return json.loads(out)


def robots(mobot) -> dict[str, dict]:
    code, out, err = mobot("list", "--json")
    assert code == 0, err
    return {robot["name"]: robot for robot in json.loads(out)["robots"]}


def test_five_robots_at_the_tutorials_positions(mobot):
    for i, (x, y) in enumerate(TUTORIAL):
        reply = spawn_json(mobot, f"tb_{i}", "--file", "mobot", "-x", x, "-y", y)
        assert reply["ok"] and reply["result"] == "OK" and not reply["renamed"]
        assert (reply["name"], reply["namespace"], reply["frame_prefix"]) == (f"tb_{i}", f"/tb_{i}", f"tb_{i}/")
    listed = robots(mobot)
    for i, (x, y) in enumerate(TUTORIAL):
        robot = listed[f"tb_{i}"]
        assert robot["namespace"] == f"/tb_{i}" and robot["has_drive"]
        assert robot["pose"]["x"] == pytest.approx(x, abs=2e-3)
        assert robot["pose"]["y"] == pytest.approx(y, abs=2e-3)
        assert robot["pose"]["z"] == pytest.approx(0.0, abs=2e-3)  # z omitted: resting on the floor
    namespaces = [robot["namespace"] for robot in listed.values()]
    assert len(namespaces) == len(set(namespaces))
    # each robot's box in its root link's frame: the footprint and heights `mobot inspect` measures
    shape = json.loads(invoke(["inspect", "mobot", "--json"]).stdout)
    footprint = shape["footprint"]
    assert (shape["bottom_z"], shape["top_z"]) == (0.0, 0.15)  # wheels to the chassis' top
    assert listed["tb_0"]["bounds"] == {"min": [footprint["xmin"], footprint["ymin"], 0.0],
                                        "max": [footprint["xmax"], footprint["ymax"], 0.15]}
    code, out, _ = mobot("list")
    assert code == 0
    assert out.splitlines()[0].split() == ["NAME", "NAMESPACE", "X", "Y", "Z", "YAW", "LINEAR", "ANGULAR"]


def test_duplicate_name_and_namespace_are_refused(mobot):
    spawn_json(mobot, "dup", "--file", "mobot", "-x", "-5", "-y", "-5")
    code, out, err = mobot("spawn", "dup", "--file", "mobot", "-x", "-7", "-y", "-5")
    assert code == 2 and out == ""
    assert err == ("mobot: error: NAME_NOT_UNIQUE: 'dup' is already the name of a robot or model in the world; "
                   "pick another name, or allow renaming (--allow-renaming)\n")
    code, _, err = mobot("spawn", "other", "--file", "mobot", "-x", "-7", "-y", "-7", "--namespace", "dup")
    assert code == 2
    assert err.startswith("mobot: error: NAMESPACE_INVALID: namespace '/dup' is already used by robot 'dup'")
    assert "other" not in robots(mobot)


def test_allow_renaming_adds_the_first_free_suffix(mobot):
    spawn_json(mobot, "twin", "--file", "mobot", "-x", "-5", "-y", "5")
    first = spawn_json(mobot, "twin", "--file", "mobot", "-x", "-6", "-y", "5", "--allow-renaming")
    second = spawn_json(mobot, "twin", "--file", "mobot", "-x", "-7", "-y", "5", "--allow-renaming")
    assert (first["name"], first["namespace"], first["renamed"]) == ("twin_0", "/twin_0", True)
    assert (second["name"], second["namespace"]) == ("twin_1", "/twin_1")
    code, out, _ = mobot("spawn", "twin", "--file", "mobot", "-x", "-8", "-y", "5", "--allow-renaming")
    assert code == 0 and out.startswith("spawned 'twin_2' (renamed from 'twin') in /twin_2 at x=-8.000 y=5.000")


def test_delete_and_unknown_names(mobot, blocker):
    spawn_json(mobot, "gone", "--file", "mobot", "-x", "-5", "-y", "8")
    code, out, _ = mobot("delete", "gone")
    assert code == 0 and out.startswith("deleted 'gone' at t=")
    assert "gone" not in robots(mobot)
    code, _, err = mobot("delete", "gone")
    assert code == 2 and err.startswith("mobot: error: NOT_FOUND: no robot named 'gone'.")
    code, _, err = mobot("odom", "blockr")
    assert code == 2 and err == "mobot: error: NOT_FOUND: no robot named 'blockr'. Did you mean 'blocker'?\n"
    code, _, err = mobot("cmd", "nobody", "--linear", "0.1")
    assert code == 2 and err.startswith("mobot: error: NOT_FOUND: no robot named 'nobody'")
    # A deleted name is free again, as in Gazebo.
    assert spawn_json(mobot, "gone", "--file", "mobot", "-x", "-5", "-y", "8")["name"] == "gone"


def test_cmd_drives_a_robot_and_odom_reads_it_back(mobot):
    spawn_json(mobot, "driver", "--file", "mobot", "-x", "3", "-y", "-3", "-Y", str(math.pi / 2))
    code, out, err = mobot("cmd", "driver", "--linear", "0.3", "--for", "2.0", "--wait")
    assert code == 0, err
    assert out.startswith("t=") and "cmd 0.000 0.000" in out  # the reply comes when the command ended
    code, out, _ = mobot("odom", "driver", "--json")
    reply = json.loads(out)
    assert reply["frame_id"] == "driver/odom" and reply["child_frame_id"] == "driver/base_footprint"
    assert reply["cmd"] == {"linear": 0.0, "angular": 0.0}
    # 0.6 m forward in the robot's frame (odom), which faces +y in the world (truth).
    assert reply["odom"]["x"] == pytest.approx(0.6, abs=0.04)
    assert reply["odom"]["y"] == pytest.approx(0.0, abs=0.01)
    assert reply["truth"]["x"] == pytest.approx(3.0, abs=0.01)
    assert reply["truth"]["y"] == pytest.approx(-3.0 + reply["odom"]["x"], abs=0.01)
    code, out, _ = mobot("cmd", "driver", "--angular", "0.5", "--for", "1.0", "--wait", "--json")
    turned = json.loads(out)
    assert turned["odom"]["yaw"] == pytest.approx(0.5, abs=0.05)
    code, out, _ = mobot("cmd", "driver", "--linear", "-0.2")
    assert code == 0 and "from step" in out
    code, out, _ = mobot("odom", "driver")
    assert code == 0 and "cmd -0.200 0.000" in out
    assert mobot("cmd", "driver")[0] == 0  # zero twist: stop


@pytest.mark.parametrize("args, result, text", [
    (["--file", "no_such_robot.urdf"], "NO_RESOURCE", "does not exist"),
    (["--file", "mobto"], "NO_RESOURCE", "Did you mean 'mobot'?"),
    (["--file", str(BAD_ROBOTS / "missing_mesh.urdf")], "MISSING_ASSETS", "cannot be found"),
    (["--file", str(BAD_ROBOTS / "syntax_error.urdf.xacro")], "RESOURCE_PARSE_ERROR", "XML syntax error"),
    (["--file", str(BAD_ROBOTS / "needs_arg.urdf.xacro")], "RESOURCE_PARSE_ERROR", "wheel_size"),
    (["--file", "mobot", "-x", "20.05", "-y", "20"], "INVALID_POSE", "into robot 'blocker'"),
    (["--file", "mobot", "-x", "9", "-y", "9", "-z", "-0.2"], "INVALID_POSE", "into the ground plane"),
    (["--file", "mobot", "--reference-frame", "nobody"], "NOT_FOUND", "reference frame 'nobody'"),
    (["--file", "mobot", "--namespace", "/bad ns"], "NAMESPACE_INVALID", "not a valid ROS namespace"),
])
def test_refused_spawns_name_their_result(mobot, blocker, args, result, text):
    code, out, err = mobot("spawn", "refused", *args)
    assert code == 2 and out == ""
    assert err.startswith(f"mobot: error: {result}: ") and text in err, err
    assert err.count("\n") == 1


def test_bad_names_and_formats(mobot, tmp_path):
    code, _, err = mobot("spawn", "9lives", "--file", "mobot")
    assert code == 2 and err.startswith("mobot: error: NAME_INVALID: '9lives' is not a valid robot name")
    world = tmp_path / "shop.world"  # a world is not a robot (SDF models are: tests/live/test_sdf_spawn.py)
    world.write_text("<sdf version='1.6'><world name='w'/></sdf>")
    code, _, err = mobot("spawn", "shop", "--file", world)
    assert code == 2 and err.startswith("mobot: error: UNSUPPORTED_FORMAT: ")
    code, _, err = mobot("spawn", "shop", "--string", world.read_text())
    assert code == 2 and err.startswith("mobot: error: UNSUPPORTED_FORMAT: ")
    mesh = tmp_path / "part.stl"
    mesh.write_text("solid x\nendsolid x\n")
    code, _, err = mobot("spawn", "part", "--file", mesh)
    assert code == 2 and err.startswith("mobot: error: UNSUPPORTED_FORMAT: ")


def test_spawn_from_text_with_args_quaternion_and_reference_frame(mobot):
    expanded = invoke(["xacro", "mobot", "lidar:=true"])
    assert expanded.exit_code == 0 and expanded.stderr == ""
    urdf = expanded.stdout
    reply = spawn_json(mobot, "texty", "--string", urdf, "-x", "12", "-y", "0")
    assert reply["pose"]["x"] == pytest.approx(12.0, abs=2e-3)
    xacro = spawn_json(mobot, "lidar_bot", "--file", "mobot", "lidar:=true", "-x", "14", "-y", "0",
                       "--quat", "0", "0", "0.7071068", "0.7071068")
    assert xacro["pose"]["yaw"] == pytest.approx(math.pi / 2, abs=1e-4)
    # -x 1 in the frame of a robot facing +y lands 1 m along +y, facing +y plus its own yaw.
    rel = spawn_json(mobot, "follower", "--file", "mobot", "--reference-frame", "lidar_bot", "-x", "1",
                     "-Y", "0.5")
    assert (rel["pose"]["x"], rel["pose"]["y"]) == pytest.approx((14.0, 1.0), abs=2e-3)
    assert rel["pose"]["yaw"] == pytest.approx(math.pi / 2 + 0.5, abs=1e-3)


def test_a_rotated_inertial_frame_spawns_on_its_wheels(mobot):
    """z omitted rests the robot on its wheels, not on its side (its base's inertia is rotated)."""
    robot = REPO / "tests" / "sim" / "robots" / "wheeldrop.urdf.xacro"
    reply = spawn_json(mobot, "tilted_inertia", "--file", str(robot), "inertial_rpy:=0.3 0.7 1.2",
                       "-x", "22", "-y", "-3", "-Y", "0.6")
    assert reply["pose"]["z"] == pytest.approx(0.035, abs=1e-3)
    assert reply["pose"]["yaw"] == pytest.approx(0.6, abs=1e-3)


def test_spawn_from_stdin(live, tmp_path):
    urdf = subprocess.run([sys.executable, "-m", "mobot_cli", "xacro", "mobot"], capture_output=True,
                          text=True, check=True, cwd=REPO).stdout
    done = subprocess.run([sys.executable, "-m", "mobot_cli", "spawn", "piped", "--stdin", "-x", "16",
                           "--endpoint", live.endpoint], input=urdf, capture_output=True, text=True, cwd=REPO)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("spawned 'piped' in /piped at x=16.000 y=0.000")


def test_spawn_reads_the_environments_stdin(live):
    urdf = invoke(["xacro", "mobot"]).stdout
    done = invoke(["spawn", "from_stdin", "--stdin", "-x", "18", "--endpoint", live.endpoint], stdin=urdf)
    assert (done.exit_code, done.stderr) == (0, "")
    assert done.stdout.startswith("spawned 'from_stdin' in /from_stdin at x=18.000 y=0.000")


def test_no_server_exits_4_and_says_how_to_start_one(tmp_path):
    for endpoint in (f"ipc://{tmp_path}/none.sock", "tcp://127.0.0.1:9"):
        done = subprocess.run([sys.executable, "-m", "mobot_cli", "list", "--endpoint", endpoint,
                               "--timeout", "0.5"], capture_output=True, text=True, cwd=REPO)
        assert done.returncode == 4
        assert done.stderr.startswith("mobot: error: no live world")
        assert "Start one with `mobot serve`" in done.stderr and "Traceback" not in done.stderr


def test_usage_errors_exit_2(mobot):
    assert mobot("spawn", "x")[0] == 2  # no --file/--string/--stdin
    code, _, err = mobot("spawn", "x", "--file", "mobot", "--quat", "0", "0", "0", "1", "-Y", "1")
    assert code == 2 and "--quat" in err
    code, _, err = mobot("cmd", "anyone", "--wait")
    assert code == 2 and "--wait needs --for" in err


def test_the_socket_is_private_and_a_second_server_is_refused(live):
    path = Path(live.endpoint[len("ipc://"):])
    assert oct(path.stat().st_mode & 0o777) == oct(0o600)
    done = subprocess.run([sys.executable, "-m", "mobot_cli", "serve", "--endpoint", live.endpoint],
                          capture_output=True, text=True, cwd=REPO, timeout=60)
    assert done.returncode == 2
    assert done.stderr.startswith(f"mobot: error: a live world (pid {live.process.pid}) already serves at ")


def test_odom_follow_prints_readings_until_interrupted(live, blocker):
    import signal

    follow = subprocess.Popen([sys.executable, "-m", "mobot_cli", "odom", blocker, "--follow", "--rate", "50",
                               "--endpoint", live.endpoint], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                              text=True, cwd=REPO)
    try:
        lines = [follow.stdout.readline() for _ in range(3)]
        follow.send_signal(signal.SIGINT)
        assert follow.wait(30) == 0
    finally:
        follow.kill()
    times = [float(line.split()[0].removeprefix("t=")) for line in lines]
    assert times == sorted(set(times)), lines  # one line per new reading
    assert all(f" {blocker}  odom x=" in line for line in lines)


def test_cmd_linear_y_moves_a_mecanum_base_and_a_diff_robot_refuses_it(mobot):
    spawn_json(mobot, "mecanum", "--file", "mecanum", "-x", "-8", "-y", "-8")
    code, out, err = mobot("cmd", "mecanum", "--linear-y", "0.25", "--for", "2.0", "--wait", "--json")
    assert code == 0, err
    reply = json.loads(out)
    assert reply["odom"]["y"] == pytest.approx(0.5, abs=0.02) and abs(reply["odom"]["x"]) < 0.01
    assert reply["truth"]["y"] == pytest.approx(-8.0 + 0.5, abs=0.02)
    assert reply["cmd"] == {"linear": 0.0, "angular": 0.0, "linear_y": 0.0}  # ended with a stop
    code, out, _ = mobot("cmd", "mecanum", "-y", "-0.1")
    assert code == 0 and "linear_y -0.1 m/s" in out
    code, out, _ = mobot("odom", "mecanum", "--json")
    moving = json.loads(out)
    assert moving["cmd"]["linear_y"] == -0.1 and robots(mobot)["mecanum"]["cmd"]["linear_y"] == -0.1
    assert moving["odom"]["vy"] == pytest.approx(-0.1, abs=0.01)
    assert moving["truth"]["vy"] == pytest.approx(-0.1, abs=0.01)
    spawn_json(mobot, "sideless", "--file", "mobot", "-x", "-8", "-y", "8")
    code, out, err = mobot("cmd", "sideless", "--linear", "0.1", "--linear-y", "0.1")
    assert code == 2 and out == ""
    assert err.startswith("mobot: error: OPERATION_FAILED: robot 'sideless' has a diff drive: it cannot move "
                          "sideways (linear_y 0.1 m/s)")
    code, out, _ = mobot("odom", "sideless", "--json")
    assert json.loads(out)["cmd"] == {"linear": 0.0, "angular": 0.0}  # refused: nothing changed


def test_a_live_spawn_holds_joints_as_a_scenario_robot_does(live, tmp_path):
    """`hold` in a spawn request, as a scenario's robot's hold: the mast robot's pole stays up (free,
    it falls aside and pulls the robot over: tests/assets/test_unseen_robots.py); a name that is no
    joint is refused, naming the closest."""
    from tests.assets.test_unseen_robots import mast_robot

    path = tmp_path / "mast.urdf"
    path.write_text(mast_robot())
    with live.client() as client:
        client.spawn("mast_held", description=str(path), pose={"x": 30.0, "y": 30.0}, hold="all")
        started = client.odom("mast_held")["t"]
        while client.odom("mast_held")["t"] < started + 2.0:  # --fast: two simulated seconds
            time.sleep(0.05)
        truth = client.odom("mast_held")["truth"]
        assert abs(truth["roll"]) < math.radians(2.0) and abs(truth["pitch"]) < math.radians(2.0)
        with pytest.raises(Exception, match="hold names 'rol_joint'.*Did you mean 'roll_joint'"):
            client.spawn("mast_bad", description=str(path), pose={"x": 33.0, "y": 30.0}, hold={"rol_joint": 0})
