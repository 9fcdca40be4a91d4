"""A loader process: the robot descriptions that spawn requests send are expanded and checked here.

LoaderPool (loader.py) starts it as ``python -m mobot_cli.live.worker FD MEMORY_BYTES SECONDS FACES LINKS``.
It limits its own address space (RLIMIT_AS) to MEMORY_BYTES, reads
``(Spawn request, rate_hz)`` pairs from the connection on FD and answers each with
``("ok", RobotPlan, notices)`` or ``("refused", Result, message)`` in JSON (mobot_cli/plan_json.py;
never a pickle, which would run code in the server if a hostile load subverted this process: the
pool validates each answer against ANSWER). Descriptions are
loaded confined (assets/sandbox.py). Each load may use SECONDS of CPU time: the kernel ends the
process past that (SIGXCPU, RLIMIT_CPU), whether or not the server is still there to notice;
the pool also kills a load that takes three times as long in wall time (one that waits).
"""

from __future__ import annotations

import math
import os
import resource
import signal
import sys
from typing import Literal

from mobot_cli.plan import RobotPlan

# What a worker sends: it is ready (its pid), a loaded robot and its notices, or a refusal (Result, message).
ANSWER = (tuple[Literal["ready"], int] | tuple[Literal["ok"], RobotPlan, list[str]]
          | tuple[Literal["refused"], int, str])
ANSWER_LIMIT = 64 << 20  # bytes: a robot has at most 16 M characters of URDF (live/spawning.py)


def main(argv: list[str]) -> int:
    """Serve load requests until the connection closes."""
    fd, memory, seconds = int(argv[0]), int(argv[1]), float(argv[2])
    bounds = (int(argv[3]), int(argv[4])) if len(argv) > 4 else None  # faces, links
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C in the terminal is the server's to handle
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = "1"  # thread pools would reserve address space for nothing
    resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
    resource.setrlimit(resource.RLIMIT_CORE, (0, 0))  # a load ended by a limit leaves no core file
    from multiprocessing.connection import Connection

    connection = Connection(fd)
    from mobot_cli.live import spawning  # warm: pydantic, the scenario model, the loaders

    _send(connection, ("ready", os.getpid()))
    while True:
        try:
            request, rate_hz = connection.recv()
        except (EOFError, OSError):
            return 0
        _cpu_budget(seconds)
        outcome = _load(spawning, request, rate_hz, memory, bounds)
        _send(connection, outcome)


def _send(connection, message: tuple) -> None:
    """One answer, as JSON; text that is not UTF-8 in a message is escaped, in a robot a refusal."""
    from mobot_cli import plan_json
    from mobot_cli.live.protocol import Result

    if message[0] == "refused":
        message = (message[0], int(message[1]), message[2].encode("utf-8", "backslashreplace").decode("utf-8"))
    try:
        data = plan_json.dump(message)
    except ValueError as exc:  # a file name that is not UTF-8 in the robot: JSON has no such text
        data = plan_json.dump(("refused", int(Result.OPERATION_FAILED), f"the loaded robot cannot be sent: {exc}"))
    connection.send_bytes(data)


def _load(spawning, request, rate_hz: int, memory: int, bounds: tuple[int, int] | None) -> tuple:
    from mobot_cli.live.protocol import Refusal, Result

    try:
        plan, notices = spawning.load_plan(request, rate_hz, bounds)
        return ("ok", plan, notices)
    except Refusal as exc:
        return ("refused", exc.result, exc.message)
    except MemoryError:
        return ("refused", Result.RESOURCE_PARSE_ERROR, "loading the description needed more than "
                f"the loader's memory limit of {memory // 2**20} MiB")
    except RecursionError:
        return ("refused", Result.RESOURCE_PARSE_ERROR, "the description nests too deeply to load")
    except Exception as exc:  # noqa: BLE001 - a bug costs this request only
        return ("refused", Result.OPERATION_FAILED, f"internal error while loading: {exc!r}")


def _cpu_budget(seconds: float) -> None:
    """Let this load use at most ``seconds`` of CPU time from now (soft RLIMIT_CPU: SIGXCPU past it)."""
    usage = resource.getrusage(resource.RUSAGE_SELF)
    used = usage.ru_utime + usage.ru_stime
    _, hard = resource.getrlimit(resource.RLIMIT_CPU)
    soft = math.ceil(used + seconds)
    if hard != resource.RLIM_INFINITY:
        soft = min(soft, hard)
    resource.setrlimit(resource.RLIMIT_CPU, (soft, hard))


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
