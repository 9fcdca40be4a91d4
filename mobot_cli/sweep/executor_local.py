"""A small pool of warm worker processes that survives its workers dying.

concurrent.futures' ProcessPoolExecutor marks every pending future broken when one worker
dies (a segfault in PyBullet, an out-of-memory kill), so a sweep could not go on past one
bad run. Here each worker is a process with a pipe: the parent waits on the pipes and on the
processes themselves, and a worker that dies or overruns its timeout is killed, its run is
marked failed, and a fresh worker takes its place. A worker dies with its sweep, even with one
killed by SIGKILL (guard.die_with_sweep). Workers stay alive for the whole sweep,
so imports, in-process caches and the PyBullet client are paid once per worker, not once per run. They come from
multiprocessing's fork server with everything a run needs imported once (sweep.preload; never
forked from the parent itself, which may run threads such as the progress bar), so a
replacement starts warm; spawn where there is no fork server (sweep/server.py).

``prestart`` starts the workers from a thread before the runs are prepared: the fork server's
imports then take the second core while the sweep reads and checks the scenario, instead of
following it. Starting a worker waits until the fork server has imported, hence the thread.
"""

from __future__ import annotations

import os
import signal
import threading
import time
from collections import deque
from multiprocessing.connection import Connection, wait
from typing import Callable, Iterable

from mobot_cli.sweep.guard import die_with_sweep
from mobot_cli.sweep.server import context, sigint_held, start_tracker
from mobot_cli.sweep.task import RunTask, Task, TaskResult, failed, run_task

OnDone = Callable[[TaskResult], None]
POLL_S = 0.5  # how often a wait wakes up to look at deadlines when none is closer
CLOSE_WAIT_S = 10.0  # how long close() waits for workers still starting
READY = "ready"  # a worker's first message: imports done, the timeout clock may start


def _worker_main(conn: Connection, runner: RunTask, sweep_pid: int) -> None:
    """A worker's life: take tasks from the pipe until told to stop (None), or the sweep ends."""
    # Ctrl-C reaches the whole process group; the parent decides what stops, not each worker.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    die_with_sweep(sweep_pid)  # a sweep killed with SIGKILL cannot stop its workers itself
    from mobot_cli.sim.bullet.clients import adopt, keep_clients
    from mobot_cli.sim.bullet.kept_body import keeping_robot_bodies
    from mobot_cli.sweep import preload  # the fork server's (this worker's copy of its client), or for spawn

    keep_clients(1)  # one run after another: each takes the PyBullet client the last one left
    adopt(preload.CLIENT)
    conn.send(READY)
    # Runs follow one another in this one thread: the first robot's body stays in the kept client for
    # the next run's same first spawn (sim/bullet/kept_body.py), the same records as a body loaded anew.
    with keeping_robot_bodies(repeated=True):
        while True:
            try:
                task = conn.recv()
            except EOFError:
                return
            if task is None:
                return
            try:
                outcome = runner(task)
            except Exception as exc:  # noqa: BLE001 - run_task never raises; a runner that does must not kill it
                outcome = failed(task.index, "error", f"{type(exc).__name__}: {exc}")
            conn.send(outcome)


class _Worker:
    """One worker process, its pipe end and the task it is running."""

    def __init__(self, ctx, runner: RunTask):
        self.conn, child = ctx.Pipe()
        self.process = ctx.Process(target=_worker_main, args=(child, runner, os.getpid()), daemon=True)
        with sigint_held():
            self.process.start()
        child.close()
        self.task: Task | None = None
        self.stopping = False  # told to stop (sent None)
        self.ready = False
        self.started: float | None = None  # when the task started; None until the worker is ready

    def give(self, task: Task) -> None:
        self.task, self.started = task, time.perf_counter() if self.ready else None
        self.conn.send(task)

    def elapsed(self) -> float:
        return 0.0 if self.started is None else time.perf_counter() - self.started

    def kill(self) -> None:
        if self.process.is_alive():
            self.process.kill()
        self.process.join(timeout=5)
        self.conn.close()


class LocalExecutor:
    """Run tasks on ``jobs`` warm worker processes; a run's failure never stops the others."""

    name = "local"

    def __init__(self, jobs: int, timeout: float | None = None, runner: RunTask = run_task, pictures: bool = True):
        self.jobs = max(1, jobs)
        self.timeout = timeout
        self.runner = runner
        self.pictures = pictures  # the workers preload the drawing of trajectory.png (sweep/server.py)
        self._early: list[_Worker] = []  # started by prestart, not yet given to run
        self._starters: list[threading.Thread] = []
        self._asked = 0  # workers prestart asked its threads for
        self._closed = threading.Event()

    def prestart(self, count: int | None = None) -> None:
        """Start workers from a thread, so that they get ready while the runs are prepared: one
        (and with it the fork server) before the runs are counted, ``min(jobs, count)`` in all
        once they are. ``close`` stops what ``run`` did not use."""
        # Without a fork server (spawn), run() starts the workers: each would import everything
        # itself, and the sweep's own imports would wait for the core. One that cannot start,
        # run() reports.
        ctx = context(self.pictures)
        if ctx.get_start_method() != "forkserver":
            return
        wanted = min(self.jobs, 1 if count is None else count) - self._asked
        if wanted <= 0:
            return
        if not self._starters:
            start_tracker()
        self._asked += wanted
        starter = threading.Thread(target=self._start_early, args=(ctx, wanted),
                                   name="mobot-sweep-prestart", daemon=True)
        self._starters.append(starter)
        starter.start()

    def _start_early(self, ctx, count: int) -> None:
        for _ in range(count):
            if self._closed.is_set():
                return
            try:
                worker = _Worker(ctx, self.runner)  # waits until the fork server has imported
            except Exception:  # noqa: BLE001  (run starts what is missing, and reports what fails)
                return
            self._early.append(worker)  # close() stops it, if run() does not take it

    def start(self) -> None:
        """Nothing to set up: workers start with prestart or with the first tasks."""

    def close(self) -> None:
        """Stop workers that prestart started and run did not take (the sweep ended early)."""
        self._closed.set()
        # Bounded: a sweep that ends must not wait on a start that never ends. A worker started
        # after this gives up dies with the sweep (guard.die_with_sweep), the fork server too.
        self._stop_all(self._take_early(CLOSE_WAIT_S))

    def _take_early(self, timeout: float | None = None) -> list[_Worker]:
        for starter in self._starters:
            starter.join(timeout)
        self._starters = []
        workers, self._early = self._early, []
        return workers

    def run(self, tasks: Iterable[Task], on_done: OnDone) -> None:
        """Run every task, calling ``on_done`` in the parent as each one ends."""
        pending = deque(tasks)
        early = self._take_early()
        slots = min(self.jobs, len(pending))
        self._stop_all(early[slots:])
        if not pending:
            return
        ctx = context(self.pictures)
        # A slot holds None after its worker was killed, until a task needs a new one.
        workers: list[_Worker | None] = early[:slots] + [_Worker(ctx, self.runner) for _ in range(slots - len(early))]
        try:
            while True:
                for i, worker in enumerate(workers):
                    if (worker is None or worker.task is None) and pending:
                        workers[i] = self._give(ctx, worker, pending.popleft())
                    elif worker is not None and worker.task is None:
                        self._tell_stop(worker)  # nothing left for it: it leaves while the others finish
                busy = [w for w in workers if w is not None and w.task is not None]
                if not busy:
                    return
                wait([w.conn for w in busy] + [w.process.sentinel for w in busy], timeout=self._wait_s(busy))
                for i, worker in enumerate(workers):
                    if worker is not None and worker.task is not None:
                        workers[i] = self._collect(worker, on_done)
        finally:
            self._stop_all([w for w in workers if w is not None])

    def _give(self, ctx, worker: _Worker | None, task: Task) -> _Worker:
        """Hand a task over; a missing worker, or one that died while idle, is replaced first."""
        if worker is not None:
            try:
                worker.give(task)
                return worker
            except (BrokenPipeError, OSError):
                worker.kill()
        worker = _Worker(ctx, self.runner)
        worker.give(task)
        return worker

    def _wait_s(self, busy: list[_Worker]) -> float:
        if self.timeout is None:
            return POLL_S
        return max(0.0, min([POLL_S] + [self.timeout - w.elapsed() for w in busy if w.started is not None]))

    def _collect(self, worker: _Worker, on_done: OnDone) -> _Worker | None:
        """Take a finished run's outcome, or fail the run of a dead or overdue worker."""
        task = worker.task
        try:
            while worker.conn.poll():
                message = worker.conn.recv()
                if message == READY:
                    worker.ready, worker.started = True, time.perf_counter()
                    continue
                worker.task = None
                on_done(message)
                return worker
        except (EOFError, OSError):
            pass  # the worker died mid-reply: treat as a crash below
        elapsed = worker.elapsed()
        if worker.process.is_alive() and (self.timeout is None or elapsed < self.timeout):
            return worker
        if worker.process.is_alive():
            outcome = failed(task.index, "timeout", f"no result after {self.timeout:g} s: the run was stopped",
                             elapsed)
        else:
            outcome = failed(task.index, "crash", _death(worker.process.exitcode), elapsed)
        worker.kill()
        on_done(outcome)
        return None

    @classmethod
    def _stop_all(cls, workers: list[_Worker]) -> None:
        """Tell every idle worker to stop first, then wait for each: they leave side by side."""
        for worker in workers:
            cls._tell_stop(worker)
        for worker in workers:
            cls._stop(worker)

    @staticmethod
    def _tell_stop(worker: _Worker) -> None:
        try:
            if worker.task is None and not worker.stopping:
                worker.conn.send(None)
                worker.stopping = True
        except (BrokenPipeError, OSError):
            pass

    @classmethod
    def _stop(cls, worker: _Worker) -> None:
        cls._tell_stop(worker)
        if worker.stopping:
            worker.process.join(timeout=2)
        worker.kill()


def _death(exitcode: int | None) -> str:
    """Words for how a worker process ended."""
    if exitcode is not None and exitcode < 0:
        try:
            name = signal.Signals(-exitcode).name
        except ValueError:
            name = f"signal {-exitcode}"
        return f"the worker process was killed by {name} (a crash in the physics engine?)"
    return f"the worker process exited with code {exitcode}"
