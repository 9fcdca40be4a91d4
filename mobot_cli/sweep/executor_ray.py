"""The same sweep on a Ray cluster: each run a Ray task, run folders shipped back as bytes.

Ray is an optional extra (``pip install "mobot-cli[ray]"``). Cluster nodes need mobot and the
robot and world files at the same paths as here (one checkout or a shared file system);
run folders come back with each task's result, so the nodes need no shared output folder.
At most as many tasks as the cluster has CPUs are in flight, so that ``--timeout`` counts
from when a run starts, not from when it was queued.
"""

from __future__ import annotations

import os
import socket
import time
from typing import Callable

from mobot_cli.common.streams import silenced
from mobot_cli.errors import Location, UsageError
from mobot_cli.sweep.task import RunTask, Task, TaskResult, failed, run_task_elsewhere

POLL_S = 0.5
REACH_TIMEOUT_S = 5.0


class RayExecutor:
    """Run tasks as Ray tasks on the cluster at ``address`` (a local instance when None)."""

    name = "ray"

    def __init__(self, jobs: int, timeout: float | None = None, address: str | None = None,
                 runner: RunTask = run_task_elsewhere):
        self.jobs, self.timeout, self.address, self.runner = max(1, jobs), timeout, address, runner
        self._started_here: bool | None = None  # None: not connected yet

    def prestart(self, count: int | None = None) -> None:
        """Nothing to start ahead: joining the cluster waits for ``start``."""

    def close(self) -> None:
        """Nothing is left running between ``run`` and the end of the sweep."""

    def start(self) -> None:
        """Join the cluster (or start a local Ray) before the sweep folder is made."""
        ray = require_ray()
        if self._started_here is None:
            self._started_here = not ray.is_initialized()
            if self._started_here:
                _connect(ray, self.address, self.jobs)

    def run(self, tasks: list[Task], on_done: Callable[[TaskResult], None]) -> None:
        """Run every task on the cluster, calling ``on_done`` here as each one ends."""
        self.start()
        ray = require_ray()
        try:
            if tasks:
                self._run(ray, list(tasks), on_done)
        finally:
            if self._started_here:
                ray.shutdown()
            self._started_here = None

    def _run(self, ray, tasks: list[Task], on_done: Callable[[TaskResult], None]) -> None:
        remote = ray.remote(num_cpus=1, max_retries=0)(self.runner)
        slots = max(1, int(ray.cluster_resources().get("CPU", self.jobs)))
        pending = list(reversed(tasks))
        running: dict = {}  # ObjectRef -> (task, start time)
        while pending or running:
            while pending and len(running) < slots:
                task = pending.pop()
                running[remote.remote(task)] = (task, time.perf_counter())
            ready, _ = ray.wait(list(running), num_returns=1, timeout=POLL_S)
            for ref in ready:
                task, started = running.pop(ref)
                on_done(_result(ray, ref, task, started))
            if self.timeout is not None:
                now = time.perf_counter()
                for ref, (task, started) in list(running.items()):
                    if now - started >= self.timeout:
                        ray.cancel(ref, force=True)
                        del running[ref]
                        on_done(failed(task.index, "timeout",
                                       f"no result after {self.timeout:g} s: the run was stopped", now - started))


def _result(ray, ref, task: Task, started: float) -> TaskResult:
    """The task's outcome, or a failed one saying how the Ray task died."""
    try:
        return ray.get(ref)
    except ray.exceptions.WorkerCrashedError:
        return failed(task.index, "crash", "the Ray worker running it died (a crash in the physics engine?)",
                      time.perf_counter() - started)
    except ray.exceptions.RayError as exc:
        return failed(task.index, "error", f"Ray: {str(exc).splitlines()[0]}", time.perf_counter() - started)


def require_ray():
    """The ray module, or a UsageError saying how to install it."""
    try:
        import ray
    except ImportError:
        raise UsageError("--executor ray needs Ray, which is not installed",
                         hint='Install it with: pip install "mobot-cli[ray]".') from None
    return ray


def _connect(ray, address: str | None, jobs: int) -> None:
    """Join the cluster at ``address``, or start a local instance of ``jobs`` CPUs."""
    if address:
        _check_reachable(address)
        _check_token(ray, address)
    try:
        if address:
            ray.init(address=address, include_dashboard=False, log_to_driver=False, logging_level="ERROR")
        else:
            ray.init(num_cpus=jobs, include_dashboard=False, log_to_driver=False, logging_level="ERROR")
    except (ConnectionError, RuntimeError, ValueError) as exc:
        raise UsageError(f"cannot reach a Ray cluster at {address or 'a new local instance'}: "
                         f"{str(exc).splitlines()[0] if str(exc) else type(exc).__name__}",
                         hint="Check --address (e.g. ray://HOST:10001 or HOST:6379) "
                              "and that the cluster is up.") from None


def _check_token(ray, address: str) -> None:
    """Refuse at once a cluster that wants a token this process does not give (Ray >= 2.5x enables
    token authentication by default): ray.init would log 20 auth errors over 20 s and then say it
    cannot connect. One GCS client call asks the cluster in milliseconds."""
    if "://" in address or ":" not in address:
        return  # ray:// clients and "auto" authenticate otherwise
    try:
        from ray._private.authentication.authentication_token_setup import maybe_enable_token_auth_if_token_available
        from ray._raylet import GcsClient
    except ImportError:
        return  # a Ray without token authentication
    maybe_enable_token_auth_if_token_available(warn_if_disabled=False)  # as ray.init does
    try:
        with silenced(2):  # Ray's core logs the refusal on fd 2 as well
            GcsClient(address=address)
    except ray.exceptions.AuthenticationError:
        token = os.environ.get("RAY_AUTH_MODE", "").lower() == "token"
        what = ("refused the token given (RAY_AUTH_TOKEN, RAY_AUTH_TOKEN_PATH or ~/.ray/auth_token)" if token
                else "uses token authentication and this process gives no token")
        raise UsageError(f"the Ray cluster at {address} {what}", location=Location(file="--address"),
                         hint="Set RAY_AUTH_MODE=token and the cluster's token in RAY_AUTH_TOKEN (or a file "
                              "named by RAY_AUTH_TOKEN_PATH, or ~/.ray/auth_token); `ray get-auth-token` "
                              "on the head node prints it.") from None
    except Exception:  # noqa: BLE001 - anything else is ray.init's to report, as before
        return


def _check_reachable(address: str) -> None:
    """Refuse an address nothing listens on at once: Ray itself retries for minutes."""
    host_port = address.split("://", 1)[-1]
    host, sep, port = host_port.rpartition(":")
    if not sep or not port.isdigit():
        return  # "auto" and other forms Ray resolves itself
    try:
        socket.create_connection((host, int(port)), timeout=REACH_TIMEOUT_S).close()
    except OSError as exc:
        raise UsageError(f"cannot reach a Ray cluster at {address}: {exc.strerror or exc}",
                         location=Location(file="--address"),
                         hint="Check the address (HOST:6379, or ray://HOST:10001) "
                              "and that the cluster is up.") from None
