"""The loader pool on its own: warm worker processes, CPU and memory limits, broken installs."""

from __future__ import annotations

import os
import pickle
import signal
import time

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mobot_cli.live import loader
from mobot_cli.live.loader import Job, Limits, LoaderPool
from mobot_cli.live.protocol import Refusal, Result
from mobot_cli.live.schema import parse
from mobot_cli.live.spawning import load_plan
from mobot_cli.plan import RobotPlan

HEAD = '<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro">'


def spawn(name: str, **fields):
    return parse({"op": "spawn", "name": name, **fields})


def finish(pool: LoaderPool, jobs: list[Job], timeout: float = 60.0) -> list[Job]:
    done: list[Job] = []
    deadline = time.monotonic() + timeout
    while len(done) < len(jobs):
        assert time.monotonic() < deadline, "the pool never finished"
        done += pool.poll()
        time.sleep(0.01)
    return done


def test_loads_come_back_as_plans_or_refusals_and_workers_stay_warm():
    pool = LoaderPool(Limits(seconds=5, memory=512 * 2**20))
    try:
        pool.start()
        good = Job(spawn("good", description="mobot"), 240)
        bad = Job(spawn("bad", urdf=HEAD + '<link name="${python.vars}"/></robot>'), 240)
        missing = Job(spawn("missing", description="no_such_robot"), 240)
        for job in (good, bad, missing):
            pool.submit(job)
        finish(pool, [good, bad, missing])
        plan, notices = good.outcome
        assert isinstance(plan, RobotPlan) and plan.name == "good" and isinstance(notices, list)
        assert isinstance(bad.outcome, Refusal) and bad.outcome.result == Result.RESOURCE_PARSE_ERROR
        assert isinstance(missing.outcome, Refusal) and missing.outcome.result == Result.NO_RESOURCE
        pids = {w.process.pid for w in pool._workers}
        again = Job(spawn("again", description="mobot"), 240)
        pool.submit(again)
        finish(pool, [again])  # by the same warm workers, not new ones (which a busy machine makes slow)
        assert {w.process.pid for w in pool._workers} == pids
    finally:
        assert pool.close() == []


def test_a_load_past_the_cpu_limit_is_stopped_and_replaced():
    load_plan(spawn("warm", description="mobot"), 240)  # the cache made warm: loads need no imports
    pool = LoaderPool(Limits(seconds=1, memory=512 * 2**20))
    try:
        pool.start()
        hostile = Job(spawn("hostile", urdf=HEAD + '<link name="${python.sum(python.range(10**12))}"/></robot>'), 240)
        pool.submit(hostile)
        finish(pool, [hostile])
        # Stopped by its limits (1 s of CPU, 3 s of wall time), not left to run: without them it would
        # run for hours. The slack is for this test's own polling on a busy machine.
        assert time.monotonic() - hostile.started < loader.WALL_FACTOR * 1 + 10  # from its dispatch
        assert hostile.outcome.result == Result.RESOURCE_PARSE_ERROR
        assert "it was stopped" in hostile.outcome.message
        after = Job(spawn("after", description="mobot"), 240)
        pool.submit(after)
        finish(pool, [after])
        assert not isinstance(after.outcome, Refusal), after.outcome.message
        assert after.outcome[0].name == "after"
    finally:
        pool.close()


def test_a_broken_installation_refuses_spawns_instead_of_restarting_forever(monkeypatch):
    monkeypatch.setattr(loader.sys, "executable", "/bin/false")
    pool = LoaderPool(Limits(seconds=5))
    try:
        pool.start()
        job = Job(spawn("x", description="mobot"), 240)
        pool.submit(job)
        finish(pool, [job], timeout=30)
        assert job.outcome.result == Result.OPERATION_FAILED
        assert "ends as soon as it starts" in job.outcome.message
        assert pool._workers == [] and pool._failed_starts == loader.FAILED_STARTS
    finally:
        pool.close()


@pytest.mark.parametrize("seconds, memory", [(10.0, 1 << 30)])
def test_the_documented_defaults(seconds, memory):
    assert Limits() == Limits(seconds=seconds, memory=memory, workers=2) and Limits().wall == 30.0


def _endless_load(pool: LoaderPool):
    """Start ``pool`` with a load named 'slow' that never ends; (its job, its worker) once it runs."""
    pool.start()
    job = Job(spawn("slow", urdf=HEAD + '<link name="${python.sum(python.range(10**12))}"/></robot>'), 240)
    pool.submit(job)
    while job.started is None:
        pool.poll()
        time.sleep(0.01)
    return job, next(w for w in pool._workers if w.job is job)


def test_a_long_load_drops_to_the_lowest_priority():
    # Limits far off (900 s of wall time), so a starved load is demoted, not stopped, first.
    pool = LoaderPool(Limits(seconds=300, memory=512 * 2**20))
    try:
        slow, worker = _endless_load(pool)
        # Quick loads are not held back: a worker runs at its parent's priority (nice 0, or the
        # nice 19 of a test run under `nice -n 19`) until it is demoted.
        assert os.getpriority(os.PRIO_PROCESS, worker.process.pid) == os.getpriority(os.PRIO_PROCESS, 0)
        # Demoted once the load has used DEMOTE_AFTER s of CPU (however long that takes on a busy machine:
        # at nice 19 beside two busy cores, minutes; the deadline only catches a load never demoted).
        deadline = time.monotonic() + 600
        while not worker.demoted and time.monotonic() < deadline:
            used = loader._cpu_seconds(worker.process.pid) - worker.cpu_at_start
            assert pool.poll() == []
            time.sleep(0.01)
        assert used >= loader.DEMOTE_AFTER - 0.05  # what it had used just before it was demoted
        assert worker.demoted and os.getpriority(os.PRIO_PROCESS, worker.process.pid) == loader.LOW_PRIORITY
    finally:
        assert [job.request.name for job in pool.close()] == ["slow"]


def test_a_load_waiting_for_the_cpu_is_not_demoted():
    """Wall time alone (a busy machine) never demotes a load: only the CPU time it used does."""
    pool = LoaderPool(Limits(seconds=30, memory=512 * 2**20))
    try:
        job, worker = _endless_load(pool)
        os.kill(worker.process.pid, signal.SIGSTOP)  # it gets no CPU, as on a machine busy with others
        try:
            while time.monotonic() < job.started + loader.DEMOTE_AFTER + 0.5:
                assert pool.poll() == []
                time.sleep(0.01)
            assert not worker.demoted
            assert os.getpriority(os.PRIO_PROCESS, worker.process.pid) == os.getpriority(os.PRIO_PROCESS, 0)
            assert worker.demote_at > time.monotonic()  # it is looked at again later
        finally:
            os.kill(worker.process.pid, signal.SIGCONT)
    finally:
        pool.close()


class _Evil:
    marker = ""

    def __reduce__(self):
        return (os.system, (f"touch {_Evil.marker}",))


@pytest.mark.parametrize("data", [
    pickle.dumps(("ok", _Evil(), [])), b"", b"\x80\x04garbage", b'["ok", {}, []]', b'["refused", 999, "x"]',
    b'["refused", "1", "x"]', b'["ok", null, []]', b'["ready"]', b'["done", 1]', b'["ready", 1, "extra"]',
], ids=repr)
def test_an_answer_that_is_not_one_is_a_reason_never_run_or_raised(data, tmp_path):
    _Evil.marker = str(tmp_path / "pwned")
    assert isinstance(loader._answer(data), str)
    assert not (tmp_path / "pwned").exists()


@settings(max_examples=200, deadline=None)
@given(st.binary(max_size=500))
def test_random_bytes_from_a_worker_are_a_reason(data):
    assert isinstance(loader._answer(data), str)


def test_answers_come_back_with_their_result():
    assert loader._answer(b'["refused", 106, "no"]') == ("refused", Result.RESOURCE_PARSE_ERROR, "no")
    assert loader._answer(b'["ready", 42]') == ("ready", 42)


def test_a_subverted_worker_refuses_its_load_and_is_replaced(tmp_path):
    """A pickle (or anything not an answer) from a worker: the load is refused, the worker killed."""
    _Evil.marker = str(tmp_path / "pwned")
    pool = LoaderPool(Limits(seconds=300, memory=512 * 2**20))
    try:
        job, worker = _endless_load(pool)
        pool._receive(worker, pickle.dumps(("ok", _Evil(), [])))
        assert job.outcome.result == Result.OPERATION_FAILED and "answer is not one" in job.outcome.message
        assert worker not in pool._workers and worker.process.wait(30) is not None
        assert not (tmp_path / "pwned").exists()
    finally:
        assert pool.close() == []


def test_a_robot_from_a_worker_equals_the_one_loaded_here():
    pool = LoaderPool(Limits(seconds=10, memory=512 * 2**20))
    try:
        pool.start()
        job = Job(spawn("same", description="mobot"), 240)
        pool.submit(job)
        finish(pool, [job])
    finally:
        pool.close()
    here, notices = load_plan(spawn("same", description="mobot"), 240)
    assert job.outcome == (here, notices) and type(job.outcome[0].drive.wheel_radius) is float
