"""`python -m mobot_cli` and the `mobot` console script: the outermost guard around the CLI.

Ctrl-C can land anywhere, even in the middle of importing the CLI or PyBullet, where it may come
out as another exception (numpy's C API turns it into an ImportError). The SIGINT handler here
notes that it fired, so whatever it turned into ends as ``mobot: interrupted``, exit 130.
Nothing heavy is imported before the handler is in place.
"""

import gc
import os
import signal
import sys

INTERRUPTED = 130  # ExitCode.INTERRUPTED, without importing mobot_cli.errors before the guard
_fired = False


def _on_sigint(signum, frame):
    global _fired
    _fired = True
    raise KeyboardInterrupt


def entry() -> None:
    """Run the `mobot` command; a Ctrl-C anywhere prints ``mobot: interrupted`` and exits 130."""
    signal.signal(signal.SIGINT, _on_sigint)
    gc.disable()  # until the command has loaded what it needs: mobot_cli/cli/startup.py
    # Pydantic looks for plugins in every installed distribution's entry points when it builds
    # mobot's first model (~10 ms a run); mobot's models have no use for them.
    os.environ.setdefault("PYDANTIC_DISABLE_PLUGINS", "__all__")
    # numpy's OpenBLAS starts a thread per core that spins for work after each call: mobot's
    # matrices are small (3x3 rotations of a scan), so those threads only took ~0.1 s of a
    # run's CPU from the other core, where the run's helper and a sweep's other worker run.
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    try:
        from mobot_cli.common.classcode import install

        install()  # dataclasses made from here on compile nothing a process before them compiled
        _start_sweep_pool(sys.argv[1:])
        _start_run_helper(sys.argv[1:])
        from mobot_cli.cli import main

        main()
    except BaseException as exc:
        signal.signal(signal.SIGINT, signal.SIG_IGN)  # a second Ctrl-C must not interrupt the exit
        if isinstance(exc, SystemExit):
            if exc.code == INTERRUPTED and _fired:
                _interrupted()  # Typer turns a KeyboardInterrupt in a command into a quiet exit 130
            if _is_run(sys.argv[1:]):
                _leave(exc.code)
            raise
        if not (_fired or isinstance(exc, KeyboardInterrupt)) or "--traceback" in sys.argv[1:]:
            raise
        _interrupted()
    finally:
        signal.signal(signal.SIGINT, signal.SIG_IGN)  # nor the interpreter's shutdown


def _start_sweep_pool(args: list[str]) -> None:
    """A local `mobot sweep` starts its fork server before anything else is imported: the
    server's imports (~0.4 s) then overlap the CLI's own instead of following them."""
    args = _command(args)
    if args[:1] != ["sweep"] or {"--help", "-h", "ray", "--executor=ray"} & set(args):
        return
    from mobot_cli.sweep.server import start_fork_server

    start_fork_server()


def _command(args: list[str]) -> list[str]:
    """The command line from its command on: without the one root option a command may follow."""
    return args[1:] if args[:1] == ["--traceback"] else args


def _is_run(args: list[str]) -> bool:
    """A `mobot run` command line (not its --help)."""
    args = _command(args)
    return args[:1] == ["run"] and not {"--help", "-h"} & set(args)


def _start_run_helper(args: list[str]) -> None:
    """`mobot run` forks its helper (run/ahead.py) before the CLI's imports, which it overlaps."""
    if _is_run(args):
        from mobot_cli.run.ahead import fork_helper

        fork_helper()


def _leave(code: object) -> None:
    """End a run without the interpreter's teardown (~30 ms of freeing numpy, PyBullet and the
    modules one by one): its files are closed by now. The exit handlers still run and the
    streams are flushed; with a thread still running (--ros2, --view), or a stream that cannot
    be flushed, the interpreter ends it as usual."""
    threading = sys.modules.get("threading")
    if not isinstance(code, int) or (threading is not None and threading.active_count() > 1):
        return
    import atexit

    atexit._run_exitfuncs()
    try:
        sys.stdout.flush()
        sys.stderr.flush()
    except (OSError, ValueError):
        return
    os._exit(code)


def _interrupted() -> None:
    """Say so and leave with 130 at once: the run loop has closed its files by now.

    Not through the interpreter's exit: when the interrupt landed in C code that ran Python
    (an extension's import), the interpreter remembers it and kills itself with SIGINT at
    the very end, which a parent process sees as -2 rather than 130.
    """
    sys.stderr.write("mobot: interrupted\n")
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    os._exit(INTERRUPTED)


if __name__ == "__main__":
    entry()
