"""A Ray cluster with token authentication (Ray >= 2.5x's default), joined without the token:
one line saying what to set, exit 2, nothing written; with the token the sweep runs."""

from __future__ import annotations

import os
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

pytest.importorskip("ray", reason="Ray is an optional extra: pip install 'mobot-cli[ray]'")

REPO = Path(__file__).resolve().parents[2]
SWEEP = REPO / "scenarios" / "sweeps" / "speeds.yaml"


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def cluster():
    """A one-CPU Ray head with RAY_AUTH_MODE=token, in a session (process group) of its own."""
    # The `ray` of this Python's environment: another one on PATH is another Ray, which the
    # client here refuses to join ("Version mismatch").
    beside = Path(sys.executable).with_name("ray")
    ray = str(beside) if beside.is_file() else shutil.which("ray")
    if ray is None:
        pytest.skip("the `ray` command is neither beside this Python nor on PATH")
    home = Path(tempfile.mkdtemp(prefix="mrh-"))  # short: Ray's socket paths live under --temp-dir
    token, port = secrets.token_hex(16), free_port()
    env = {**os.environ, "HOME": str(home), "RAY_AUTH_MODE": "token", "RAY_AUTH_TOKEN": token}
    head = subprocess.Popen([ray, "start", "--head", "--block", "--port", str(port), "--num-cpus", "1",
                             "--include-dashboard", "false", "--temp-dir", str(home / "t")],
                            env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        deadline = time.monotonic() + 300
        while True:
            try:
                socket.create_connection(("127.0.0.1", port), timeout=1).close()
                break
            except OSError:
                if head.poll() is not None or time.monotonic() > deadline:
                    pytest.fail(f"ray start exited with {head.returncode} or never listened")
                time.sleep(0.2)
        yield f"127.0.0.1:{port}", token, home
    finally:
        for signum in (signal.SIGTERM, signal.SIGKILL):
            try:
                os.killpg(head.pid, signum)  # the head and every Ray process it started
            except ProcessLookupError:
                break
            time.sleep(5)
        head.wait(30)
        shutil.rmtree(home, ignore_errors=True)


def sweep(address: str, out: Path, home: Path, **auth: str) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if not k.startswith("RAY_AUTH")}
    env.update(HOME=str(home / "client"), **auth)  # no ~/.ray/auth_token of the user's
    return subprocess.run([sys.executable, "-m", "mobot_cli", "sweep", str(SWEEP), "--executor", "ray",
                           "--address", address, "--out", str(out), "--quiet"],
                          cwd=REPO, env=env, capture_output=True, text=True, timeout=600)


def test_without_the_token_one_line_says_what_to_set(cluster, tmp_path):
    address, _, home = cluster
    done = sweep(address, tmp_path / "out", home)
    assert done.returncode == 2, done.stderr
    assert done.stderr.count("\n") == 1 and "Traceback" not in done.stderr, done.stderr
    assert f"the Ray cluster at {address} uses token authentication" in done.stderr
    assert "Set RAY_AUTH_MODE=token" in done.stderr
    assert not (tmp_path / "out").exists()


def test_a_wrong_token_is_named_as_such(cluster, tmp_path):
    address, _, home = cluster
    done = sweep(address, tmp_path / "out", home, RAY_AUTH_MODE="token", RAY_AUTH_TOKEN=secrets.token_hex(16))
    assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
    assert "refused the token given" in done.stderr


def test_with_the_token_the_sweep_runs(cluster, tmp_path):
    address, token, home = cluster
    done = sweep(address, tmp_path / "out", home, RAY_AUTH_MODE="token", RAY_AUTH_TOKEN=token)
    assert done.returncode in (0, 1), done.stderr  # speeds.yaml's slow and fast runs fail their expectations
    assert len((tmp_path / "out" / "results.csv").read_text().splitlines()) == 7  # a header and 6 runs
