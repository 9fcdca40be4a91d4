"""`mobot run`'s helper process (run/ahead.py): the same run folder, messages and exit codes with
it as without it (MOBOT_HELPER=0), a run that finishes when the helper dies, and no helper left
behind. These run `python -m mobot_cli` as a user's shell does: the helper is forked only there."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mobot_cli.run import ahead

REPO = Path(__file__).resolve().parents[2]
CORES = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
needs_two_cores = pytest.mark.skipif(CORES < 2, reason="the helper is forked only with two cores or more")
LIDAR = """version: 1
name: seen
world: house
duration: 3
seed: 4
robots:
  - name: r
    pose: {x: -3.0, y: -2.5}
    args: {lidar: "true"}
    sensors: {lidar: {rate_hz: 10, samples: 90, noise_stddev: 0.02}}
    commands: [{at: 0.5, linear: 0.3, angular: 0.4}]
"""
# Runs `mobot` as the console script does, and says what the helper did, when the run has ended.
PROBE = """
import atexit, os, signal, sys
from mobot_cli.run import ahead
seen = {"pid": None, "plan": None, "painted": None, "facts": None, "parsed": None}
take, prepared, painted = ahead.take, ahead.Ahead.prepared, ahead.Ahead.painted
def take_():
    helper = take()
    seen["pid"] = helper.pid if helper else None
    return helper
def prepared_(self):
    plan = prepared(self)
    seen["plan"] = plan is not None
    if os.environ.get("KILL_HELPER"):
        os.kill(self.pid, signal.SIGKILL)
    return plan
def painted_(self):
    seen["painted"] = painted(self)
    return seen["painted"]
ahead.take, ahead.Ahead.prepared, ahead.Ahead.painted = take_, prepared_, painted_
def told():  # the URDF facts the helper sent, and whether this process imported an XML parser
    seen["facts"] = len(getattr(sys.modules.get("mobot_cli.sim.urdf_file"), "_known", ()))
    seen["parsed"] = "xml.etree.ElementTree" in sys.modules
    print("helper", seen)
atexit.register(told)
sys.argv = ["mobot", *sys.argv[1:]]
from mobot_cli.__main__ import entry
entry()
"""


def _mobot(*args: object, helper: bool = True, probe: bool = False, **env: str) -> subprocess.CompletedProcess:
    command = [sys.executable, "-c", PROBE] if probe else [sys.executable, "-m", "mobot_cli"]
    environ = {**os.environ, "MOBOT_HELPER": "1" if helper else "0", **env}
    return subprocess.run([*command, *map(str, args)], capture_output=True, text=True, cwd=REPO, env=environ,
                          timeout=300)


def _seen(done: subprocess.CompletedProcess) -> dict:
    line = done.stdout.strip().splitlines()[-1]
    assert line.startswith("helper "), done.stdout + done.stderr
    return eval(line[len("helper "):])  # noqa: S307 - our own probe's dict of None, bool and int


def _files(folder: Path) -> dict[str, bytes]:
    """Every file of a run folder by its relative path; summary.json without its wall-clock figures."""
    files = {}
    for path in sorted(p for p in folder.rglob("*") if p.is_file()):
        data = path.read_bytes()
        if path.name == "summary.json":
            record = json.loads(data)
            record.pop("wall_time")
            record.pop("real_time_factor")
            data = json.dumps(record).encode()
        files[str(path.relative_to(folder))] = data
    return files


def _gone(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    return False


@needs_two_cores
@pytest.mark.parametrize("scenario", ["quickstart", "coverage", "lidar"])
def test_the_run_folder_is_the_same_with_the_helper_as_without(scenario, tmp_path):
    path = REPO / "scenarios" / f"{scenario}.yaml"
    if scenario == "lidar":
        path = tmp_path / "lidar.yaml"
        path.write_text(LIDAR)
    helped = _mobot("run", path, "--out", tmp_path / "helped", "--quiet", "--duration", "3", probe=True)
    alone = _mobot("run", path, "--out", tmp_path / "alone", "--quiet", "--duration", "3", helper=False)
    # (coverage's expectations fail when it is cut short: exit 1, said the same way)
    assert helped.returncode == alone.returncode in (0, 1) and helped.stderr == alone.stderr
    seen = _seen(helped)
    assert seen["plan"] is True and seen["painted"] is True  # the helper did prepare and draw
    assert seen["facts"] == 1  # and worked out the file and friction of the robot's URDF
    if scenario == "quickstart":  # (a coverage run loads the floor plan, whose code imports XML parsing)
        assert seen["parsed"] is False
    assert _gone(seen["pid"])  # and was reaped
    files = _files(tmp_path / "helped")
    assert {"trajectory.png", "scenario.yaml", "summary.json"} <= set(files)
    assert files == _files(tmp_path / "alone")


@needs_two_cores
@pytest.mark.parametrize("args", [
    ["run", "tests/bad/unknown_key.yaml"],
    ["run", "tests/bad/sensor_missing_link.yaml", "--json"],
    ["run", "scenarios/quickstart.yaml", "--set", "robots[0].pose.x=wide"],
    ["run", "scenarios/quickstart.yaml", "--set", "duration=-1", "--traceback"],
    ["run", "no/such/scenario.yaml"],
    ["run", "scenarios/quickstart.yaml", "--out", "README.md"],
    # read by the run itself (the YAML side), validated by the helper (pydantic): either side's error
    ["run", "tests/bad/malformed_yaml.yaml"],
    ["run", "tests/bad/not_a_mapping.yaml"],
    ["run", "tests/bad/missing_version.yaml"],
    ["run", "tests/bad/yaml_date.yaml"],
    ["run", "tests/bad/robot_syntax_error.yaml"],
    ["run", "tests/bad/world_spawn_in_furniture.yaml"],
    ["run", "scenarios/quickstart.yaml", "--set", "seed"],
    ["run", "scenarios/quickstart.yaml", "--set", "robots.nobody.pose.x=1"],
    ["run", "scenarios/quickstart.yaml", "--set", "version=2"],
])
def test_bad_input_reads_the_same_with_the_helper_as_without(args):
    helped, alone = _mobot(*args, probe=True), _mobot(*args, helper=False)
    assert helped.returncode == alone.returncode == 2
    assert helped.stderr == alone.stderr and "Traceback" not in helped.stderr
    assert helped.stdout.splitlines()[:-1] == alone.stdout.splitlines()
    pid = _seen(helped)["pid"]  # None: Typer refused the line before the run began
    assert pid is None or _gone(pid)


@needs_two_cores
def test_each_side_of_a_run_imports_only_its_own_share():
    """The run's process reads the YAML and writes the record without pydantic (and makes the
    record's classes only at its end); its helper validates and resolves without PyYAML, and draws
    without PyBullet (each ~10-60 ms of start-up the other pays instead)."""
    code = ("import sys; import mobot_cli.{}; print(sorted(m for m in ('yaml', 'pydantic', 'PIL', 'pybullet', "
            "'mobot_cli.run.record') if m in sys.modules))")
    def imported(modules: str) -> list[str]:
        done = subprocess.run([sys.executable, "-c", code.format(modules)], capture_output=True, text=True,
                              check=True, cwd=REPO)
        return eval(done.stdout)  # noqa: S307 - a list of module names printed above
    run_side = "cli.runner, mobot_cli.run.execute, mobot_cli.scenario.overrides, mobot_cli.scenario.yamlsource"
    assert imported(run_side) == ["pybullet", "yaml"]
    before_loop = ("import sys; import mobot_cli.{}; print(sorted(m for m in ('json', 'difflib', 'hashlib', "
                   "'xml.etree.ElementTree') if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", before_loop.format(run_side)], capture_output=True, text=True,
                          check=True, cwd=REPO)
    assert done.stdout.split() == ["[]"]  # the summary's JSON, a misspelt name's suggestions, the URDF's file
    assert imported("run.prepare") == ["pydantic"]
    drawing = ("import sys; import mobot_cli.run.prepare; from mobot_cli.run.picture import draw, preload; preload(); "
               "print(sorted(m for m in ('PIL', 'pybullet', 'yaml') if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", drawing], capture_output=True, text=True, check=True, cwd=REPO)
    assert done.stdout.split() == ["['PIL']"]  # the helper draws without the engine


def test_a_run_whose_helper_dies_draws_its_picture_itself(tmp_path):
    scenario = REPO / "scenarios" / "quickstart.yaml"
    killed = _mobot("run", scenario, "--out", tmp_path / "killed", "--quiet", probe=True, KILL_HELPER="1")
    alone = _mobot("run", scenario, "--out", tmp_path / "alone", "--quiet", helper=False)
    assert killed.returncode == 0 and killed.stderr == ""
    seen = _seen(killed)
    assert seen["plan"] is True and seen["painted"] is None  # it could not even be asked
    assert _files(tmp_path / "killed") == _files(tmp_path / "alone")


@needs_two_cores
def test_ctrl_c_in_the_loop_leaves_no_helper_and_no_half_picture(tmp_path):
    proc = subprocess.Popen([sys.executable, "-c", PROBE, "run", "scenarios/quickstart.yaml", "--out",
                             str(tmp_path / "run"), "--quiet", "--duration", "600"], cwd=REPO,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env={**os.environ, "MOBOT_HELPER": "1"})
    deadline = time.monotonic() + 60
    while not (tmp_path / "run" / "odom").exists() and time.monotonic() < deadline:
        time.sleep(0.05)  # the loop has started: the folder is made after the robots are placed
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    assert (proc.returncode, err) == (130, "mobot: interrupted\n")
    assert json.loads((tmp_path / "run" / "summary.json").read_text())["status"] == "interrupted"
    assert not list((tmp_path / "run").glob("*.tmp"))


def test_a_helper_stopped_while_it_writes_the_picture_leaves_no_temporary_file(tmp_path):
    """Ctrl-C while the helper writes trajectory.png: the run kills it, and removes the temporary
    sibling write_bytes_atomic was filling in the helper (named after the helper's pid)."""
    out = tmp_path / "trajectory.png"
    reader, writer = os.pipe()  # the helper's pipes, as Ahead holds them
    opened_r, opened_w = os.pipe()
    pid = os.fork()
    if pid == 0:  # stands for the helper, killed inside write_bytes_atomic with its file half-written
        try:
            import mobot_cli.common.files as files

            class Stuck:  # the temporary file, open: it says so and never finishes
                def __init__(self, fd):
                    self.fd = fd

                def __enter__(self):
                    return self

                def __exit__(self, *exc):
                    os.close(self.fd)

                def write(self, data):
                    os.write(opened_w, b"!")
                    time.sleep(60)
            files.os.fdopen = lambda fd, mode: Stuck(fd)
            files.write_bytes_atomic(out, b"x" * 100)
        finally:
            os._exit(0)
    os.close(opened_w)
    assert os.read(opened_r, 1) == b"!"
    os.close(opened_r)
    left = [p.name for p in tmp_path.iterdir()]
    assert len(left) == 1 and left[0].startswith(".trajectory.png.") and left[0].endswith(".tmp")
    (tmp_path / f".trajectory.png.{pid + 1}.abcd.tmp").write_bytes(b"")  # another process's: kept
    helper = ahead.Ahead(pid, reader, writer)
    helper.painting = out
    helper.close()
    assert [p.name for p in tmp_path.iterdir()] == [f".trajectory.png.{pid + 1}.abcd.tmp"]
    assert _gone(pid)


def test_without_the_entry_point_there_is_no_helper(tmp_path):
    from mobot_cli.cli import invoke

    out = invoke(["run", REPO / "scenarios" / "quickstart.yaml", "--out", tmp_path / "out", "--quiet",
                  "--duration", "0.2"])
    assert out.exit_code == 0 and ahead.take() is None


def test_mobot_helper_0_forks_nothing(tmp_path):
    done = _mobot("run", "scenarios/quickstart.yaml", "--out", tmp_path / "out", "--quiet", "--duration", "0.2",
                  helper=False, probe=True)
    assert done.returncode == 0 and _seen(done) == {"pid": None, "plan": None, "painted": None, "facts": 0,
                                                    "parsed": True}  # (it parsed the URDF itself)


LEAVES = st.none() | st.booleans() | st.floats(allow_nan=False) | st.text() | st.binary(max_size=200_000)


@settings(max_examples=30, deadline=None)
@given(value=st.recursive(LEAVES, lambda inner: st.lists(inner, max_size=4)
                          | st.dictionaries(st.text(max_size=5), inner, max_size=4), max_leaves=8))
def test_values_cross_the_pipe_whole_whatever_their_size(value):
    reader, writer = os.pipe()
    try:
        sending = threading.Thread(target=ahead._send, args=(writer, value))  # larger than a pipe holds
        sending.start()
        assert ahead._receive(reader) == value
        sending.join()
    finally:
        os.close(writer)
    assert ahead._receive(reader) is None  # the other end closed: None, not an error
    os.close(reader)
