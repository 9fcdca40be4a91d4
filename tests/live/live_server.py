"""A real `mobot serve` process for tests: started, waited for, and always killed afterwards."""

from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

from mobot_cli.errors import LiveWorldError
from mobot_cli.live.client import Client

REPO = Path(__file__).resolve().parents[2]
START_TIMEOUT = 600.0  # s; only catches a server that never answers (a cold start on a busy machine is slow)


class LiveProcess:
    """`python -m mobot_cli serve ARGS --endpoint ipc://<short tmp path>` in a subprocess."""

    def __init__(self, *args: str, cache_dir: Path, out: Path | None = None, ready: bool = True,
                 endpoint: str | None = None, python: str | None = None):
        # Unix socket paths must stay short: pytest's tmp_path is often too long for one.
        self.folder = Path(tempfile.mkdtemp(prefix="mobot-t-"))
        self.endpoint = endpoint or f"ipc://{self.folder / 's.sock'}"
        self.out = out
        command = [python or sys.executable, "-m", "mobot_cli", "serve", *args, "--endpoint", self.endpoint]
        if out is not None:
            command += ["--out", str(out)]
        env = {k: v for k, v in os.environ.items()
               if k not in ("MOBOT_RESOURCE_PATH", "ROS_PACKAGE_PATH", "AMENT_PREFIX_PATH",
                            "GZ_SIM_RESOURCE_PATH", "GAZEBO_MODEL_PATH", "MOBOT_ENDPOINT", "MOBOT_SERVER_KEY")}
        env["MOBOT_CACHE_DIR"] = str(cache_dir)
        env["MOBOT_KEYS_DIR"] = str(cache_dir.parent / "mobot-keys")  # conftest's: never the user's keys
        self.log = open(self.folder / "server.log", "w+")
        self.process = subprocess.Popen(command, cwd=REPO, env=env, stdout=self.log, stderr=subprocess.STDOUT)
        if ready:
            self._wait_ready()

    def _wait_ready(self) -> None:
        deadline = time.monotonic() + START_TIMEOUT
        while time.monotonic() < deadline:
            if self.process.poll() is not None:
                raise RuntimeError(f"mobot serve exited with {self.process.returncode}: {self.output()}")
            if self.endpoint.endswith(":*"):  # the server picks the port and prints it
                found = re.search(r" at (tcp://\S+?), ", self.output())
                if found is None:
                    time.sleep(0.05)
                    continue
                self.endpoint = found.group(1)
            try:
                with Client(self.endpoint, timeout=0.5) as client:
                    client.ping()
                return
            except LiveWorldError:
                time.sleep(0.05)
        output = self.output()  # before kill() closes the log
        self.kill()
        raise RuntimeError(f"mobot serve did not answer within {START_TIMEOUT} s: {output}")

    def client(self, timeout: float = 30.0) -> Client:
        return Client(self.endpoint, timeout=timeout)

    def output(self) -> str:
        self.log.flush()
        return (self.folder / "server.log").read_text()

    def signal(self, signum: int = signal.SIGTERM, timeout: float = 30.0) -> int:
        """Send a signal and wait for the exit code."""
        self.process.send_signal(signum)
        return self.process.wait(timeout)

    def wait(self, timeout: float = 30.0) -> int:
        return self.process.wait(timeout)

    def kill(self) -> None:
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait(10)
        self.log.close()
        shutil.rmtree(self.folder, ignore_errors=True)


def wait_for_step(client: Client, step: int, timeout: float = 60.0) -> dict:
    """Ping until the world reaches ``step`` (a --fast world gets there in well under a second)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        reply = client.ping()
        if reply["step"] >= step:
            return reply
        time.sleep(0.01)
    raise AssertionError(f"the world did not reach step {step} within {timeout} s")


@contextmanager
def fast_world(tmp_path_factory) -> Iterator[LiveProcess]:
    """A `--fast` empty world for a test module, with the session's cache; it must outlive the
    module's tests (a server that died fails the module), then it is killed."""
    server = LiveProcess("--fast", cache_dir=tmp_path_factory.getbasetemp() / "mobot-cache")
    try:
        yield server
        assert server.process.poll() is None, f"the server died: {server.output()}"
    finally:
        server.kill()
