"""multiprocessing's fork server for a sweep's workers, and Ctrl-C held back while one starts.

The pool (executor_local) starts its workers from the fork server, which imports everything a
run needs once (sweep.preload), so that every worker forked from it starts warm; plain spawn
where the platform has no fork server.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import signal
import threading


@contextlib.contextmanager
def sigint_held():
    """Ctrl-C held back while a worker (and with the first one, the fork server) is started.

    SIGINT is blocked in this thread while it starts them, so the new Python inherits it blocked
    through exec and an interrupt cannot kill it mid-import with a traceback on the terminal
    (the fork server ignores it for good once its imports are done; a worker ignores it first
    thing). In the main thread a Ctrl-C that comes meanwhile is noted, not lost, and raised once
    the start is done; in another thread the main thread takes it as usual.
    """
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    # multiprocessing's resource tracker unblocks SIGINT in the starting thread right after it
    # starts, which would undo the hold for the fork server the same call starts next: it is
    # started first. The one call of mobot into multiprocessing outside its manual (a public
    # name of a public module, no underscore); without it, a Ctrl-C while the fork server
    # imports kills it with a traceback on the terminal.
    from multiprocessing import resource_tracker

    resource_tracker.ensure_running()
    if threading.current_thread() is not threading.main_thread():
        signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
        try:
            yield
        finally:
            signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
        return
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


def start_tracker() -> None:
    """Start multiprocessing's resource tracker now, with Ctrl-C held back (sigint_held starts it
    first): the pool's thread then starts the fork server, and a Ctrl-C that comes while the
    tracker starts is raised here, in the main thread, rather than in the middle of an import."""
    with sigint_held():
        pass


def context(pictures: bool = True):
    """The fork server with mobot imported where the platform has one (with the drawing of
    trajectory.png when the runs draw ``pictures``), else plain spawn. A process has one fork
    server: the first sweep's preload is every later sweep's in it (a later sweep with pictures
    then loads the drawing in each worker's first run).

    What starting a worker imports is imported here, in the calling (main) thread, so that the
    pool's starter thread imports nothing: a Ctrl-C that lands in the main thread in the middle
    of an import can leave Python's import lock taken (the interrupt is raised between taking it
    and the code that gives it back), and a thread that imports after that waits for ever, and
    the sweep with it, silent."""
    if "forkserver" in multiprocessing.get_all_start_methods():
        from multiprocessing import popen_forkserver, resource_tracker  # noqa: F401  (forkserver, spawn, ...)

        ctx = multiprocessing.get_context("forkserver")
        ctx.set_forkserver_preload(["mobot_cli.sweep.preload_pictures" if pictures else "mobot_cli.sweep.preload"])
        return ctx
    return multiprocessing.get_context("spawn")
