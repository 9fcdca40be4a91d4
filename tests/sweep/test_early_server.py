"""`mobot sweep` starts the fork server before the CLI imports anything (mobot_cli.__main__)."""

from __future__ import annotations

import pytest

import mobot_cli.__main__ as entry
from mobot_cli.common.forked import close_fds_but
from mobot_cli.sweep import server


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
    monkeypatch.setattr(server, "start_fork_server", lambda: calls.append(1) or True)
    entry._start_sweep_pool(args)
    assert calls == ([1] if starts else [])


def test_the_early_server_is_the_one_the_sweep_uses():
    from multiprocessing import forkserver

    assert server.start_fork_server() is True
    first = forkserver._forkserver._forkserver_pid
    assert first is not None
    server.start_fork_server()  # prestart's call finds it running
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
        from mobot_cli.sweep import server
        server.start_fork_server()
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


def _in_fresh_python(script: str) -> str:
    """Run ``script`` in a new interpreter (no pytest threads) and return what it printed."""
    import os
    import subprocess
    import sys
    import textwrap

    done = subprocess.run([sys.executable, "-c", textwrap.dedent(script)], capture_output=True, text=True,
                          timeout=60, env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    assert done.returncode == 0 and "Traceback" not in done.stderr, done.stderr
    return done.stdout


SERVER_COMMAND = """
    import os, select, threading, time
    from multiprocessing import forkserver, resource_tracker
    from mobot_cli.sweep import server
    THREADS
    read, write = os.pipe()  # a pipe this process writes to: its reader waits for every writer
    server.start_fork_server()
    os.close(write)
    eof = bool(select.select([read], [], [], 5.0)[0]) and os.read(read, 1) == b""
    for pid in (forkserver._forkserver._forkserver_pid, resource_tracker._resource_tracker._pid):
        with open(f"/proc/{pid}/cmdline", "rb") as f:
            print(f.read() != open("/proc/self/cmdline", "rb").read(), end=" ")  # a command of its own
    print(eof)
"""


def test_the_server_and_its_tracker_are_forked_without_a_new_interpreter():
    """A sweep forks them before its imports (no second interpreter to start), and they keep
    none of the sweep's other files open, as new programs would not: a pipe's reader still
    sees its end when the sweep closes it."""
    out = _in_fresh_python(SERVER_COMMAND.replace("THREADS", ""))
    assert out.split() == ["False", "False", "True"]  # neither has a command of its own; the pipe ended


def test_a_process_with_threads_starts_them_as_new_interpreters():
    """Forking while another thread may hold a lock could copy it held for good: spawned then."""
    threads = "stop = threading.Event(); threading.Thread(target=stop.wait, daemon=True).start()"
    out = _in_fresh_python(SERVER_COMMAND.replace("THREADS", threads))
    assert out.split() == ["True", "True", "True"]


def test_closing_all_but_some_descriptors_keeps_those(tmp_path):
    import os

    opened = [os.open(tmp_path / f"f{i}", os.O_CREAT | os.O_WRONLY) for i in range(4)]
    pid = os.fork()
    if pid == 0:  # the child reports, through its exit code, which of them it still has
        close_fds_but({0, 1, 2, opened[1], opened[3]})
        alive = [_is_open(fd) for fd in (0, 1, 2, *opened)]
        os._exit(sum(1 << i for i, up in enumerate(alive) if up))
    _, status = os.waitpid(pid, 0)
    for fd in opened:
        os.close(fd)
    assert os.waitstatus_to_exitcode(status) == 0b1010111  # 0, 1, 2 and the 2nd and 4th file


def _is_open(fd: int) -> bool:
    import os

    try:
        os.fstat(fd)
        return True
    except OSError:
        return False
