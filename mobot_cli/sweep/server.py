"""multiprocessing's fork server for a sweep's workers: started early, and without a new interpreter.

`mobot sweep` starts it first thing (mobot_cli.__main__), before its own imports, with
everything a run needs imported in it (sweep.preload); the pool (executor_local) forks its
workers from it. Ctrl-C is held back while it starts, and it is forked from the sweep process
while that has no other thread, rather than started as a new interpreter.
"""

from __future__ import annotations

import contextlib
import gc
import multiprocessing
import os
import signal
import threading

from mobot_cli.common.forked import close_fds_but


@contextlib.contextmanager
def sigint_held():
    """Ctrl-C held back while a process (the fork server, or a spawned worker) is started.

    SIGINT is blocked in this thread while it forks, so the new Python inherits it blocked
    through exec and an interrupt cannot kill it mid-import with a traceback on the terminal
    (the fork server ignores it for good once its imports are done; a worker ignores it first
    thing). A Ctrl-C that comes meanwhile is noted, not lost, and raised once the start is done.
    """
    if threading.current_thread() is not threading.main_thread() or not hasattr(signal, "pthread_sigmask"):
        yield
        return
    # multiprocessing's resource tracker unblocks SIGINT in this thread right after it starts
    # (resource_tracker.ensure_running), which would undo the hold for the fork server the same
    # call then starts: it is started first, and blocks SIGINT for its own start.
    from multiprocessing import resource_tracker

    resource_tracker.ensure_running()
    came: list = []
    old = signal.signal(signal.SIGINT, lambda signum, frame: came.append(frame))
    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})  # one held back is noted now
        signal.signal(signal.SIGINT, old)  # (signal.signal runs pending handlers first)
    if came and callable(old):
        old(signal.SIGINT, came[-1])  # the sweep's own handler: KeyboardInterrupt
    elif came and old != signal.SIG_IGN:
        raise KeyboardInterrupt


def start_fork_server() -> bool:
    """Start the fork server, with everything a run needs imported, if it is not running; False
    where there is none or it cannot start. It returns at once: the server imports in the
    background. `mobot sweep` calls it first thing (mobot_cli.__main__), before its own imports."""
    if context().get_start_method() != "forkserver":
        return False
    from multiprocessing import forkserver

    try:
        with _forked_helpers(), sigint_held():
            forkserver.ensure_running()
    except OSError:
        return False
    return True


@contextlib.contextmanager
def _forked_helpers():
    """The fork server and its resource tracker forked from this process instead of started as
    new interpreters, while this process has no other thread (`mobot sweep` before its imports).

    multiprocessing starts each as ``python -c CODE`` (util.spawnv_passfds): an interpreter's
    start, ~0.1 s here, before the fork server's first import, and a third process on two cores.
    A fork runs the same CODE at once, with the same file descriptors kept, stdin left to CODE
    to close, and the garbage collector on as in a new interpreter. Anything other than that
    ``-c`` form, or a process with threads (a fork could copy a lock another thread holds), is
    started as multiprocessing would."""
    from multiprocessing import util

    spawn = util.spawnv_passfds

    def forked(path, args, passfds):
        if threading.active_count() > 1 or len(args) < 2 or args[-2] != "-c":
            return spawn(path, args, passfds)
        pid = os.fork()
        if pid:
            return pid
        code = 1
        try:
            close_fds_but({0, 1, 2, *map(int, passfds)})
            gc.enable()
            exec(args[-1], {"__name__": "__main__"})
            code = 0
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else int(exc.code is not None)
        except BaseException:  # noqa: BLE001  (shown, as the interpreter it stands for would)
            import traceback

            traceback.print_exc()
        finally:
            os._exit(code)

    util.spawnv_passfds = forked
    try:
        yield
    finally:
        util.spawnv_passfds = spawn


def context():
    """The fork server with mobot imported where the platform has one, else plain spawn."""
    if "forkserver" in multiprocessing.get_all_start_methods():
        ctx = multiprocessing.get_context("forkserver")
        ctx.set_forkserver_preload(["mobot_cli.sweep.preload"])
        return ctx
    return multiprocessing.get_context("spawn")
