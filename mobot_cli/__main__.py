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
    # mobot's first model; mobot's models have no use for them.
    os.environ.setdefault("PYDANTIC_DISABLE_PLUGINS", "__all__")
    # numpy's OpenBLAS starts a thread per core that spins for work after each call: mobot's
    # matrices are small (3x3 rotations of a scan), so those threads only take CPU from the
    # other cores, where a sweep's other workers run.
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    try:
        from mobot_cli.cli import main

        main()
    except BaseException as exc:
        signal.signal(signal.SIGINT, signal.SIG_IGN)  # a second Ctrl-C must not interrupt the exit
        if isinstance(exc, SystemExit):
            if exc.code == INTERRUPTED and _fired:
                _interrupted()  # Typer turns a KeyboardInterrupt in a command into a quiet exit 130
            raise
        if not (_fired or isinstance(exc, KeyboardInterrupt)) or "--traceback" in sys.argv[1:]:
            raise
        _interrupted()
    finally:
        signal.signal(signal.SIGINT, signal.SIG_IGN)  # nor the interpreter's shutdown


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
