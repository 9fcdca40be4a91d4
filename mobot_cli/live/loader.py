"""A small pool of warm loader processes (worker.py) for the descriptions spawn requests send.

The world's thread never expands or checks a description a client sent: it hands the request
to an idle worker process and goes on stepping. A load that uses more CPU time than the limit
is ended by the kernel (RLIMIT_CPU), one that waits three times as long in wall time is killed
here, and one that needs more memory than the limit fails in the worker (RLIMIT_AS). Either
way the spawn is refused with RESOURCE_PARSE_ERROR and a fresh worker takes the dead one's place.
Workers are reused between loads, so a warm load costs milliseconds; one is started with the
server, and while every worker is loading one more is started (up to ``Limits.workers``), so a
slow or hostile load never makes the next one cold.
Workers run at normal priority, so a spawn is quick on a busy machine too; a load that has used
DEMOTE_AFTER seconds of CPU time drops to nice 19 and its worker is replaced when it is done.
CPU time, not wall time: on a busy machine a legitimate load waits for the CPU, and demoting it
then would starve it past the wall-time limit.
"""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from collections import deque
from dataclasses import dataclass, field
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any

from mobot_cli.live.protocol import Refusal, Result
from mobot_cli.live.schema import Spawn
from mobot_cli.live.worker import ANSWER, ANSWER_LIMIT

WALL_FACTOR = 3  # CPU time is the limit (fair on a busy machine); wall time only catches waiting
FAILED_STARTS = 3  # workers that end before they are ready, in a row: the installation is broken
# A load that has used this many seconds of CPU (a cold one takes about one) drops to the lowest
# priority, so the world's thread wins the CPU; its worker is replaced once it is done.
DEMOTE_AFTER = 2.0
_TICK = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100
LOW_PRIORITY = 19
_PACKAGE_PARENT = str(Path(__file__).resolve().parent.parent.parent)  # the folder holding mobot_cli/


@dataclass(frozen=True)
class Limits:
    """What one load may take (CPU seconds, bytes of address space), how many run at once, and
    what one robot (mesh faces, links) and the world (robots) may cost the world's thread."""

    seconds: float = 10.0  # of CPU time; a load that waits is stopped after WALL_FACTOR times as long
    memory: int = 1 << 30  # 1 GiB
    workers: int = 2
    # PyBullet parses a robot's meshes on the world's thread, at a cost for every face: the limit
    # keeps what a spawn holds the world up short.
    faces: int = 100_000  # of all the robot's meshes, collision and visual, each use counted
    links: int = 200
    robots: int = 100  # in the world, scenario robots included: 1,000 bring it to 5 % of real time

    @property
    def wall(self) -> float:
        """Wall seconds after which a load is stopped even if it used little CPU (it waits on something)."""
        return WALL_FACTOR * self.seconds


@dataclass
class Job:
    """One description to load; ``outcome`` is (RobotPlan, notices) or a Refusal once done."""

    request: Spawn
    rate_hz: int
    owner: Any = None  # whatever the caller needs to answer it
    outcome: Any = None
    started: float | None = None


@dataclass
class _Worker:
    process: subprocess.Popen
    connection: Connection
    ready: bool = False
    job: Job | None = None
    deadline: float = field(default=float("inf"))
    demote_at: float = field(default=float("inf"))
    demoted: bool = False
    cpu_at_start: float = 0.0  # the worker's CPU seconds when its job was sent


class LoaderPool:
    """Load spawn requests in worker processes, within ``limits``; results come back in ``poll()``."""

    def __init__(self, limits: Limits = Limits()):
        self.limits = limits
        self._workers: list[_Worker] = []
        self._queue: deque[Job] = deque()
        self._dying: list[subprocess.Popen] = []
        self._done: list[Job] = []
        self._failed_starts = 0

    def start(self) -> None:
        """Start the first worker now, so the first spawn finds it warm."""
        if not self._workers:
            self._workers.append(self._start_worker())
        from mobot_cli import plan_json

        plan_json.adapter(ANSWER)  # the checker of answers, built while the worker starts (~0.1 s)

    def submit(self, job: Job) -> None:
        """Queue a load; it starts as soon as a worker is free."""
        self._queue.append(job)
        self._dispatch()
        if self._failed_starts >= FAILED_STARTS and not self._workers:
            self._refuse_queue()

    @property
    def pending(self) -> int:
        """Loads queued or running: robots that may join the world soon."""
        return len(self._queue) + sum(w.job is not None for w in self._workers)

    @property
    def busy(self) -> bool:
        """True while loads are queued, running or unanswered, or a worker is starting: poll() has work."""
        return bool(self._queue or self._done) or any(w.job is not None or not w.ready for w in self._workers)

    def fds(self) -> tuple[int, ...]:
        """File descriptors to wait on: workers starting up or loading."""
        return tuple(w.connection.fileno() for w in self._workers if w.job is not None or not w.ready)

    def next_deadline(self) -> float | None:
        """Monotonic time at which poll() has something to do for a running load: demote or stop it."""
        deadlines = [w.deadline if w.demoted else w.demote_at for w in self._workers if w.job is not None]
        return min(deadlines) if deadlines else None

    def poll(self) -> list[Job]:
        """Finished loads (results, time-outs, deaths), in the order they finished."""
        now = time.monotonic()
        for worker in list(self._workers):
            if worker.job is None and worker.ready:
                continue
            if worker.job is not None and now >= worker.deadline:
                self._fail(worker, Result.RESOURCE_PARSE_ERROR, "loading the description took longer "
                           f"than {self.limits.wall:g} s of wall time; it was stopped")
                continue
            if worker.job is not None and not worker.demoted and now >= worker.demote_at:
                self._demote_if_busy(worker, now)
            try:
                if worker.connection.poll(0):
                    self._receive(worker, worker.connection.recv_bytes(ANSWER_LIMIT))
            except (EOFError, OSError):
                self._failed_starts = 0 if worker.ready else self._failed_starts + 1
                self._fail(worker, Result.RESOURCE_PARSE_ERROR, self._death(worker))
        self._reap()
        self._dispatch()
        if self._failed_starts >= FAILED_STARTS and not self._workers:
            self._refuse_queue()
        done, self._done = self._done, []
        return done

    def close(self) -> list[Job]:
        """Stop every worker; returns the loads that never finished."""
        unfinished = list(self._queue) + [w.job for w in self._workers if w.job is not None]
        for worker in self._workers:
            self._kill(worker)
        self._workers, self._queue = [], deque()
        for process in self._dying:
            try:
                process.wait(5)
            except subprocess.TimeoutExpired:
                pass
        self._dying = []
        return unfinished

    # -- workers ----------------------------------------------------------------------------

    def _start_worker(self) -> _Worker:
        ours, theirs = socket.socketpair()
        env = {**os.environ, "PYTHONPATH": os.pathsep.join(
            p for p in (_PACKAGE_PARENT, os.environ.get("PYTHONPATH")) if p)}
        try:
            process = subprocess.Popen(
                [sys.executable, "-m", "mobot_cli.live.worker", str(theirs.fileno()),
                 str(self.limits.memory), str(self.limits.seconds), str(self.limits.faces),
                 str(self.limits.links)],
                pass_fds=(theirs.fileno(),), stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                env=env)
        finally:
            theirs.close()
        return _Worker(process, Connection(ours.detach()))

    def _dispatch(self) -> None:
        while self._queue:
            idle = next((w for w in self._workers if w.ready and w.job is None), None)
            if idle is None:
                break
            job = self._queue.popleft()
            try:
                idle.connection.send((job.request, job.rate_hz))
            except (OSError, ValueError) as exc:  # a dead worker, or a request that cannot be pickled
                job.outcome = Refusal(Result.OPERATION_FAILED, f"internal error: the loader failed: {exc!r}")
                self._done.append(job)
                self._retire(idle)
                continue
            job.started = time.monotonic()
            idle.job, idle.deadline = job, job.started + self.limits.wall
            idle.demote_at = job.started + DEMOTE_AFTER
            idle.cpu_at_start = _cpu_seconds(idle.process.pid) or 0.0
        self._keep_warm()

    def _keep_warm(self) -> None:
        """While every worker is loading, start one more (up to the limit), so the next load finds it warm."""
        if self._failed_starts >= FAILED_STARTS:
            return  # it would end at start again: no restart loop
        if all(w.job is not None for w in self._workers) and len(self._workers) < self.limits.workers:
            self._workers.append(self._start_worker())

    def _refuse_queue(self) -> None:
        while self._queue:
            job = self._queue.popleft()
            job.outcome = Refusal(Result.OPERATION_FAILED, "the loader process ends as soon as it starts "
                                  "(see the server's error output); nothing can be spawned")
            self._done.append(job)

    def _receive(self, worker: _Worker, data: bytes) -> None:
        message = _answer(data)
        if isinstance(message, str):  # not an answer: the worker is not to be trusted with another load
            self._fail(worker, Result.OPERATION_FAILED, f"internal error: the loader's answer is not one ({message})")
            return
        if message[0] == "ready":
            worker.ready, self._failed_starts = True, 0
            return
        job, worker.job, worker.deadline = worker.job, None, float("inf")
        if job is None:
            return
        if message[0] == "ok":
            job.outcome = (message[1], message[2])
        else:
            job.outcome = Refusal(message[1], message[2])
        self._done.append(job)
        if worker.demoted:  # it cannot get its priority back: a fresh worker takes its place
            self._retire(worker)

    def _demote_if_busy(self, worker: _Worker, now: float) -> None:
        """Demote a load that has used DEMOTE_AFTER s of CPU; one that waited for the CPU is looked at again later."""
        cpu = _cpu_seconds(worker.process.pid)
        used = DEMOTE_AFTER if cpu is None else cpu - worker.cpu_at_start  # no /proc: wall time it is
        if used >= DEMOTE_AFTER:
            self._demote(worker)
        else:
            worker.demote_at = now + max(DEMOTE_AFTER - used, 0.1)

    def _demote(self, worker: _Worker) -> None:
        """A long load yields the CPU to the world (raising a child's nice needs no privilege)."""
        worker.demoted = True
        try:
            os.setpriority(os.PRIO_PROCESS, worker.process.pid, LOW_PRIORITY)
        except OSError:
            pass  # it just ended: poll() sees that next

    def _death(self, worker: _Worker) -> str:
        """Why a worker's connection closed, as the refused spawn's message."""
        try:
            code = worker.process.wait(0.2)  # its connection closed because it ended: no real wait
        except subprocess.TimeoutExpired:
            code = None
        if code == -signal.SIGXCPU:
            return (f"loading the description took more than the {self.limits.seconds:g} s limit of CPU "
                    "time; it was stopped")
        return (f"the loader process ended while loading the description (exit status {code}); it may "
                f"have needed more than the {self.limits.memory // 2**20} MiB memory limit")

    def _fail(self, worker: _Worker, result: Result, message: str) -> None:
        if worker.job is not None:
            worker.job.outcome = Refusal(result, message)
            self._done.append(worker.job)
            worker.job = None
        self._retire(worker)

    def _retire(self, worker: _Worker) -> None:
        """Kill a worker and keep the pool warm with a fresh one."""
        self._kill(worker)
        self._workers.remove(worker)
        self._keep_warm()

    def _kill(self, worker: _Worker) -> None:
        worker.connection.close()
        if worker.process.poll() is None:
            worker.process.kill()
        self._dying.append(worker.process)

    def _reap(self) -> None:
        self._dying = [process for process in self._dying if process.poll() is None]


def _answer(data: bytes) -> tuple | str:
    """A worker's answer checked (it is untrusted: a hostile load may have subverted the worker),
    with its Result made one; or why it is not an answer."""
    from mobot_cli import plan_json

    try:
        message = plan_json.load(ANSWER, data, ANSWER_LIMIT)
        return (message[0], Result(message[1]), message[2]) if message[0] == "refused" else message
    except ValueError as exc:  # not JSON, not an ANSWER, or a Result that does not exist
        return str(exc)


def _cpu_seconds(pid: int) -> float | None:
    """CPU seconds (user + system) process ``pid`` has used, from /proc; None where there is none."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as stat:
            fields = stat.read().rsplit(b")", 1)[1].split()
    except (OSError, IndexError):
        return None
    return (int(fields[11]) + int(fields[12])) / _TICK  # utime, stime: fields 14 and 15 of stat
