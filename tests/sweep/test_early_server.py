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


def test_a_ctrl_c_while_the_server_imports_does_not_kill_it():
    """Ctrl-C reaches the fork server too (one process group); it must neither die nor print a
    traceback while it imports, although multiprocessing's resource tracker, started by the same
    call, unblocks SIGINT behind the hold."""
    import os
    import signal
    import subprocess
    import sys
    import textwrap

    script = textwrap.dedent("""
        import os, signal, sys, time
        from multiprocessing import forkserver
        from mobot_cli.sweep import executor_local
        executor_local.start_fork_server()
        pid = forkserver._forkserver._forkserver_pid
        for _ in range(20):  # Ctrl-C while it starts and imports
            os.kill(pid, signal.SIGINT)
            time.sleep(0.02)
        time.sleep(0.5)
        print(os.waitpid(pid, os.WNOHANG)[0] == 0)
    """)
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60,
                          env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    assert done.stdout.strip() == "True", done.stderr
    assert "Traceback" not in done.stderr
