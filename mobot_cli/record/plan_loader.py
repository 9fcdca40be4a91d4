"""A run folder's scenario.yaml resolved again, as the live world loads a client's robot.

The robots and world it names are expanded in a child process that limits its own CPU time
(RLIMIT_CPU) and address space (RLIMIT_AS), inside the sandbox of live spawns
(assets/sandbox.py: no ``$(eval)`` past plain values, no Python internals, no ``$(env)``, reads
only inside the run folder and the resource search path), and with an audit hook that refuses
to open any other file: no ``/etc/passwd`` or ``~/.ssh`` through a world, a mesh or an include,
and no FIFO that would block the open. The parent waits at most ``plan_wall`` seconds.
"""

from __future__ import annotations

import math
import os
import pickle
import stat
import subprocess
import sys
from pathlib import Path

from mobot_cli.errors import Location, MobotError

_PACKAGE_PARENT = str(Path(__file__).resolve().parent.parent.parent)  # the folder holding mobot_cli/
WALL_FACTOR = 6  # CPU time is the limit; wall time only catches a load that waits (busy machines wait too)
_SYSTEM = ("/dev/", "/proc/", "/sys/", "/usr/", "/lib", "/opt/")  # shared libraries, CPU counts, zoneinfo
_SANDBOX_FAULTS = ("OutsideRoots", "Forbidden", "LimitExceeded", "Refused")
# The child's sys.path[0] is the package's folder, never the current one (which may be the run folder).
_BOOT = "import sys; sys.path[0] = {!r}; from mobot_cli.record.plan_loader import main; sys.exit(main(sys.argv[1:]))"


class PlanRefused(MobotError):
    """The sandbox refused what a run folder's scenario.yaml names, or a limit stopped resolving it."""


def load_plan(folder: Path, limits):
    """The Plan of ``folder/scenario.yaml``; PlanRefused when the sandbox refused it, a limit
    stopped it or it does not resolve."""
    wall = WALL_FACTOR * limits.plan_seconds
    command = [sys.executable, "-c", _BOOT.format(_PACKAGE_PARENT), str(folder.resolve()),
               str(limits.plan_memory), str(limits.plan_seconds)]
    where = Location(file=folder / "scenario.yaml")
    hint = "A run folder's robots and world are loaded as a live spawn's are: see docs/security.md."
    try:
        done = subprocess.run(command, stdin=subprocess.DEVNULL, capture_output=True, timeout=wall)
    except subprocess.TimeoutExpired:
        raise PlanRefused(f"resolving it took more than {wall:g} s", location=where, hint=hint) from None
    if done.returncode != 0 or not done.stdout:
        why = (f"more than {limits.plan_seconds:g} s of CPU time" if done.returncode == -24  # SIGXCPU
               else f"an exit code of {done.returncode}" + _last_line(done.stderr))
        raise PlanRefused(f"resolving it stopped with {why}", location=where, hint=hint)
    kind, payload = pickle.loads(done.stdout)
    if kind == "ok":
        return payload
    name, message = payload
    message = " ".join(message.split())  # one line, whatever the loaders said
    if name in _SANDBOX_FAULTS:
        raise PlanRefused(f"refused: {message}", location=where, hint=hint)
    raise PlanRefused(f"does not resolve: {message}", location=where,
                      hint="A run folder's robots and world must load as they did when it was written.")


def _last_line(stderr: bytes) -> str:
    lines = stderr.decode("utf-8", "replace").strip().splitlines()
    return f" ({' '.join(lines[-1].split())[:200]})" if lines else ""


def main(argv: list[str]) -> int:
    """In the child: resolve FOLDER/scenario.yaml within MEMORY bytes and SECONDS of CPU; pickle to stdout."""
    import resource

    folder, memory, seconds = Path(argv[0]), int(argv[1]), float(argv[2])
    out = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)  # anything the loaders print goes to stderr, not into the answer
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = "1"  # thread pools would reserve address space for nothing
    resource.setrlimit(resource.RLIMIT_CORE, (0, 0))
    resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
    resource.setrlimit(resource.RLIMIT_CPU, (math.ceil(seconds), math.ceil(seconds) + 1))
    from mobot_cli.assets import sandbox
    from mobot_cli.assets.resources import ResourceResolver
    from mobot_cli.common.cache import cache_dir
    from mobot_cli.scenario.prepare import prepare

    roots = [folder, *ResourceResolver(folder).roots]
    readable = [*roots, cache_dir(), *(p for p in sys.path[1:] if p), sys.prefix, sys.base_prefix]
    refusals = _guard_opens([str(Path(p).resolve()) for p in readable])
    try:
        with sandbox.confined(roots):
            answer = ("ok", prepare(folder / "scenario.yaml").plan)
    except MobotError as exc:
        refused = refusals or _refused(exc, (sandbox.OutsideRoots, sandbox.Forbidden, sandbox.LimitExceeded))
        answer = ("error", ("Refused" if refused else type(exc).__name__, str(exc)))
    except MemoryError:
        answer = ("error", ("LimitExceeded", f"it needs more than {memory >> 20} MiB of memory"))
    except RecursionError:
        answer = ("error", ("LimitExceeded", "it nests too deeply to load"))
    except Exception as exc:  # noqa: BLE001 - whatever a damaged file trips in a loader is this folder's fault
        answer = ("error", ("Refused" if isinstance(exc, PermissionError) else type(exc).__name__,
                            f"{type(exc).__name__}: {exc}"))
    out.write(pickle.dumps(answer))
    out.close()
    return 0


def _refused(exc: BaseException, kinds: tuple[type, ...]) -> bool:
    """True when the sandbox refused something on the way to ``exc`` (loaders wrap its errors)."""
    seen: BaseException | None = exc
    for _ in range(20):
        if seen is None:
            return False
        if isinstance(seen, kinds) or "a live spawn may" in str(seen):
            return True
        seen = seen.__cause__ or seen.__context__
    return False


def _guard_opens(readable: list[str]) -> list[str]:
    """Refuse (PermissionError) to open a file outside ``readable`` and the system's folders, or a
    FIFO; the refused paths are listed in the list returned (a loader may turn the error into its own)."""
    allowed = tuple(p.rstrip("/") + "/" for p in readable) + _SYSTEM
    refusals: list[str] = []

    def hook(event: str, args: tuple) -> None:
        if event != "open" or not isinstance(args[0], (str, bytes, os.PathLike)):
            return
        path = os.path.realpath(os.fsdecode(args[0]))
        if not (path + "/").startswith(allowed):
            refusals.append(path)
            raise PermissionError(f"{path} is outside the folders a run folder's scenario may read")
        try:
            mode = os.stat(path).st_mode
        except OSError:
            return
        if not (stat.S_ISREG(mode) or stat.S_ISDIR(mode)) and not path.startswith(("/dev/", "/proc/", "/sys/")):
            refusals.append(path)
            raise PermissionError(f"{path} is not a regular file")

    sys.addaudithook(hook)
    return refusals
