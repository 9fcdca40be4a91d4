"""`mobot sweep` starts the fork server before the CLI imports anything (mobot_cli.__main__)."""

from __future__ import annotations

import pytest

import mobot_cli.__main__ as entry
from mobot_cli.sweep import executor_local


@pytest.mark.parametrize("args, starts", [
    (["sweep", "s.yaml", "--grid", "seed=1,2"], True),
    (["--traceback", "sweep", "s.yaml"], True),
    (["sweep", "s.yaml", "--executor", "local"], True),
    (["sweep", "--help"], False),
    (["sweep", "s.yaml", "-h"], False),
    (["sweep", "s.yaml", "--executor", "ray"], False),
    (["sweep", "s.yaml", "--executor=ray"], False),
    (["run", "sweep"], False),
    ([], False),
])
def test_only_a_local_sweep_starts_the_server_early(monkeypatch, args, starts):
    calls = []
    monkeypatch.setattr(executor_local, "start_fork_server", lambda: calls.append(1) or True)
    entry._start_sweep_pool(args)
    assert calls == ([1] if starts else [])


def test_the_early_server_is_the_one_the_sweep_uses():
    from multiprocessing import forkserver

    assert executor_local.start_fork_server() is True
    first = forkserver._forkserver._forkserver_pid
    assert first is not None
    executor_local.start_fork_server()  # prestart's call finds it running
    assert forkserver._forkserver._forkserver_pid == first
