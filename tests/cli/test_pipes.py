"""A pipe that closes early is not an error (issue 26): `mobot odom r --follow | head -2` exits 0,
quietly, whatever the command was printing. Real processes on real pipes, and a real `mobot serve`."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.live.live_server import REPO, LiveProcess

WAIT = 600.0  # s; only catches a command that never ends (a busy machine starts Python slowly)
TINY = "version: 1\nname: tiny\nduration: 1\nrobots:\n  - name: r\n"


def mobot(*args: object) -> list[str]:
    return [sys.executable, "-m", "mobot_cli", *map(str, args)]


def into_a_closed_pipe(command: list[str]) -> tuple[int, str]:
    """Run ``command`` with stdout on a pipe whose reader has gone already: (exit code, stderr)."""
    read, write = os.pipe()
    os.close(read)  # every write to stdout now fails with EPIPE
    try:
        done = subprocess.run(command, stdout=write, stderr=subprocess.PIPE, text=True, cwd=REPO, timeout=WAIT)
    finally:
        os.close(write)
    return done.returncode, done.stderr


def first_line_then_close(command: list[str]) -> tuple[str, int, str]:
    """Read one line of ``command``'s stdout and close the pipe, as `| head -1` does:
    (the line, exit code, stderr)."""
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=REPO)
    try:
        line = process.stdout.readline()
        process.stdout.close()
        code = process.wait(WAIT)
        return line, code, process.stderr.read()
    finally:
        process.kill()
        process.stderr.close()


@pytest.fixture(autouse=True)
def buffered(monkeypatch):
    """The commands' stdout buffered, as a user's shell leaves it: PYTHONUNBUFFERED (set on some
    CI machines) would write every line at once and hide output still buffered at exit."""
    monkeypatch.delenv("PYTHONUNBUFFERED", raising=False)


@pytest.fixture(scope="module")
def live(tmp_path_factory):
    """A --fast live world with a robot 'r' and a robot 'lid' that carries a lidar."""
    server = LiveProcess("--fast", cache_dir=tmp_path_factory.getbasetemp() / "mobot-cache")
    try:
        with server.client() as client:
            client.spawn("r", description="mobot", pose={"x": 0.0, "y": 0.0})
            client.spawn("lid", description="mobot", args={"lidar": "true"}, pose={"x": 3.0, "y": 0.0})
        yield server
    finally:
        server.kill()


@pytest.fixture
def tiny(tmp_path) -> Path:
    path = tmp_path / "tiny.yaml"
    path.write_text(TINY)
    return path


@pytest.mark.parametrize("follow", [["odom", "r"], ["scan", "lid"], ["odom", "r", "--json"]])
def test_following_into_head_ends_quietly_with_0(live, follow):
    line, code, err = first_line_then_close(mobot(*follow, "--follow", "--rate", "50", "--endpoint", live.endpoint))
    assert line.startswith("t=") or json.loads(line)["ok"] is True, line
    assert (code, err) == (0, "")


@pytest.mark.parametrize("command", [["list"], ["list", "--json"], ["odom", "r"], ["scan", "lid", "--json"]])
def test_live_clients_print_into_a_closed_pipe_quietly(live, command):
    assert into_a_closed_pipe(mobot(*command, "--endpoint", live.endpoint)) == (0, "")


def test_run_json_and_help_into_a_closed_pipe(tiny, tmp_path):
    assert into_a_closed_pipe(mobot("run", tiny, "--json", "--out", tmp_path / "run")) == (0, "")
    assert (tmp_path / "run" / "summary.json").is_file()  # the run was whole before it printed
    assert into_a_closed_pipe(mobot("--help")) == (0, "")
    assert into_a_closed_pipe(mobot("run", "--help")) == (0, "")


def test_several_runs_stop_when_their_reader_has_gone(tiny, tmp_path):
    """`mobot run a b c --json | head -1`: the first summary is read, the command ends at the next."""
    names = [tmp_path / f"{stem}.yaml" for stem in "abc"]
    for name in names:
        name.write_text(TINY)
    line, code, err = first_line_then_close(mobot("run", *names, "--json", "--out", tmp_path / "runs"))
    assert line.startswith('{"status": "ok"') and (code, err) == (0, "")
    assert (tmp_path / "runs" / "a" / "summary.json").is_file()


def test_an_error_keeps_its_exit_code_when_stderr_has_gone(tmp_path):
    """The reader of stderr gone too: the error's code, 2, not 0; no traceback anywhere."""
    read, write = os.pipe()
    os.close(read)
    try:
        done = subprocess.run(mobot("check", tmp_path / "missing.yaml"), stdout=write, stderr=write,
                              cwd=REPO, timeout=WAIT)
    finally:
        os.close(write)
    assert done.returncode == 2


def test_sweep_json_into_a_closed_pipe(tiny, tmp_path):
    command = mobot("sweep", tiny, "--grid", "robots.r.pose.x=0,1", "--jobs", "1", "--json", "--out", tmp_path / "s")
    assert into_a_closed_pipe(command) == (0, "")
    assert len((tmp_path / "s" / "results.csv").read_text().splitlines()) == 3  # header and both runs


def test_what_c_code_prints_stays_out_of_a_json_answer(tmp_path):
    """PyBullet's mesh importer prints `b3Warning ... Unsupported texture image format` to file
    descriptor 1 itself when a mesh's material names a 1-bit colormap PNG (husarion_gz_worlds'
    walls): `mobot run --json` stays JSON, and the warning goes to stderr."""
    from PIL import Image

    image = Image.new("P", (8, 8))
    image.putpalette([255, 255, 255, 0, 0, 0])
    image.save(tmp_path / "wall.png", bits=1)
    (tmp_path / "wall.mtl").write_text("newmtl m\nKd 1 1 1\nmap_Kd wall.png\n")
    corners = [(x, y, z) for x in (-1.0, 1.0) for y in (0.0, 0.1) for z in (0.0, 1.0)]
    faces = [(1, 2, 4), (1, 4, 3), (5, 7, 8), (5, 8, 6), (1, 5, 6), (1, 6, 2),
             (3, 4, 8), (3, 8, 7), (1, 3, 7), (1, 7, 5), (2, 6, 8), (2, 8, 4)]
    vertices = "".join(f"v {x} {y} {z}\n" for x, y, z in corners)
    (tmp_path / "wall.obj").write_text("mtllib wall.mtl\nusemtl m\n" + vertices
                                       + "".join(f"f {a} {b} {c}\n" for a, b, c in faces))
    (tmp_path / "w.sdf").write_text(
        "<?xml version='1.0'?><sdf version='1.9'><world name='w'><include><uri>model://ground_plane</uri></include>"
        "<model name='wall'><static>true</static>"
        "<pose>0 2 0 0 0 0</pose><link name='l'><collision name='c'><geometry><mesh><uri>wall.obj</uri></mesh>"
        "</geometry></collision></link></model></world></sdf>")
    (tmp_path / "s.yaml").write_text(TINY.replace("name: tiny\n", "name: tiny\nworld: w.sdf\n"))
    done = subprocess.run(mobot("run", tmp_path / "s.yaml", "--json", "--out", tmp_path / "out"), capture_output=True,
                          text=True, cwd=REPO, timeout=WAIT,
                          env={**os.environ, "MOBOT_CACHE_DIR": str(tmp_path / "cache")})
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["status"] == "ok"
    assert "Unsupported texture image format" in done.stderr
