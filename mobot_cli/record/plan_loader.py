"""A run folder's scenario.yaml resolved again, as the live world loads a client's robot.

The robots and world it names are expanded in a child process that limits its own CPU time
(RLIMIT_CPU) and address space (RLIMIT_AS), inside the sandbox of live spawns
(assets/sandbox.py: no ``$(eval)`` past plain values, no Python internals, no ``$(env)``, reads
only inside the run folder and the resource search path), and with an audit hook that refuses
to open any other file: no ``/etc/passwd`` or ``~/.ssh`` through a world, a mesh or an include,
and no FIFO that would block the open. The parent waits at most ``plan_wall`` seconds.

The child answers in JSON (mobot_cli/plan_json.py), never a pickle: the parent reads at most
``plan_reply`` bytes of it and validates it against the answer's types, so a child subverted by
the folder can at worst make the folder refused, never run code in the parent.
"""

from __future__ import annotations

import math
import os
import selectors
import stat
import subprocess
import sys
import time
from pathlib import Path
from typing import Callable

from mobot_cli.errors import Location, MobotError
from mobot_cli.plan import Plan

_PACKAGE_PARENT = str(Path(__file__).resolve().parent.parent.parent)  # the folder holding mobot_cli/
WALL_FACTOR = 6  # CPU time is the limit; wall time only catches a load that waits (busy machines wait too)
_SYSTEM = ("/dev/", "/proc/", "/sys/", "/usr/", "/lib", "/opt/")  # shared libraries, CPU counts, zoneinfo
_SANDBOX_FAULTS = ("OutsideRoots", "Forbidden", "LimitExceeded", "Refused")
# The child's answer, [plan, null] or [null, [name, message]]: the plan, or what stopped it.
REPLY = tuple[Plan | None, tuple[str, str] | None]
MESSAGE_CHARS = 4000  # of an error's message: one line, however long the child made it
_STDERR_KEPT = 1 << 16  # bytes of the child's error output kept: its last line is told
_HINT = "A run folder's robots and world are loaded as a live spawn's are: see docs/security.md."
# The child's sys.path[0] is the package's folder, never the current one (which may be the run folder).
_BOOT = "import sys; sys.path[0] = {!r}; from mobot_cli.record.plan_loader import main; sys.exit(main(sys.argv[1:]))"


class PlanRefused(MobotError):
    """The sandbox refused what a run folder's scenario.yaml names, or a limit stopped resolving it."""


def load_plan(folder: Path, limits):
    """The Plan of ``folder/scenario.yaml``; PlanRefused when the sandbox refused it, a limit
    stopped it or it does not resolve."""
    from mobot_cli import plan_json

    wall = WALL_FACTOR * limits.plan_seconds
    command = [sys.executable, "-c", _BOOT.format(_PACKAGE_PARENT), str(folder.resolve()),
               str(limits.plan_memory), str(limits.plan_seconds)]
    where = Location(file=folder / "scenario.yaml")
    cap = limits.plan_reply
    try:
        # pydantic's checker of the answer is built while the child resolves the folder
        returncode, stdout, stderr = run_bounded(command, wall, cap, meanwhile=lambda: plan_json.adapter(REPLY))
    except subprocess.TimeoutExpired:
        raise PlanRefused(f"resolving it took more than {wall:g} s", location=where, hint=_HINT) from None
    except AnswerTooLong:
        raise PlanRefused(f"resolving it gave an answer longer than {cap / (1 << 20):g} MiB", location=where,
                          hint=_HINT + " MOBOT_RUN_FOLDER_LIMITS=plan_reply=MIB raises the limit.") from None
    if returncode != 0 or not stdout:
        why = (f"more than {limits.plan_seconds:g} s of CPU time" if returncode == -24  # SIGXCPU
               else f"an exit code of {returncode}" + _last_line(stderr))
        raise PlanRefused(f"resolving it stopped with {why}", location=where, hint=_HINT)
    return read_reply(folder, stdout, cap)


def read_reply(folder: Path, data: bytes, cap: int) -> Plan:
    """The plan in the child's answer ``data`` (untrusted: at most ``cap`` bytes of JSON that
    validates as a REPLY); PlanRefused for an error it reports or an answer that is not one."""
    from mobot_cli import plan_json

    where = Location(file=folder / "scenario.yaml")
    try:
        plan, error = plan_json.load(REPLY, data, cap)
    except ValueError as exc:
        raise PlanRefused(f"resolving it gave an answer that is not a plan: {exc}", location=where,
                          hint=_HINT) from None
    if (plan is None) == (error is None):
        raise PlanRefused("resolving it gave an answer that is not a plan: it holds "
                          f"{'neither a plan nor an error' if plan is None else 'both a plan and an error'}",
                          location=where, hint=_HINT)
    if plan is not None:
        return plan
    name, message = error
    message = " ".join(message.split())[:MESSAGE_CHARS]  # one line, whatever the loaders said
    if name in _SANDBOX_FAULTS:
        raise PlanRefused(f"refused: {message}", location=where, hint=_HINT)
    raise PlanRefused(f"does not resolve: {message}", location=where,
                      hint="A run folder's robots and world must load as they did when it was written.")


class AnswerTooLong(Exception):
    """The child wrote more than the answer may hold."""


def run_bounded(command: list[str], wall: float, cap: int,
                meanwhile: Callable[[], object] | None = None) -> tuple[int, bytes, bytes]:
    """Run the child (and ``meanwhile()`` here as it starts): its exit code, its output (more than
    ``cap`` bytes: AnswerTooLong, and it is killed) and the end of its error output;
    subprocess.TimeoutExpired after ``wall`` seconds."""
    deadline = time.monotonic() + wall
    child = subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    out, err = bytearray(), bytearray()
    try:
        if meanwhile is not None:
            meanwhile()
        with selectors.DefaultSelector() as selector:
            selector.register(child.stdout, selectors.EVENT_READ, out)
            selector.register(child.stderr, selectors.EVENT_READ, err)
            while selector.get_map():
                left = deadline - time.monotonic()
                if left <= 0:
                    raise subprocess.TimeoutExpired(command, wall)
                for key, _ in selector.select(left):
                    chunk = os.read(key.fd, 1 << 16)
                    if not chunk:
                        selector.unregister(key.fileobj)
                    key.data.extend(chunk)
                if len(out) > cap:
                    raise AnswerTooLong
                del err[:-_STDERR_KEPT]
        return child.wait(max(deadline - time.monotonic(), 0.0)), bytes(out), bytes(err)
    finally:
        if child.poll() is None:
            child.kill()
        child.wait()
        child.stdout.close()
        child.stderr.close()


def _last_line(stderr: bytes) -> str:
    lines = stderr.decode("utf-8", "replace").strip().splitlines()
    return f" ({' '.join(lines[-1].split())[:200]})" if lines else ""


def main(argv: list[str]) -> int:
    """In the child: resolve FOLDER/scenario.yaml within MEMORY bytes and SECONDS of CPU; the
    answer (REPLY) to stdout as JSON."""
    import resource

    folder, memory, seconds = Path(argv[0]), int(argv[1]), float(argv[2])
    out = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)  # anything the loaders print goes to stderr, not into the answer
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = "1"  # thread pools would reserve address space for nothing
    resource.setrlimit(resource.RLIMIT_CORE, (0, 0))
    resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
    resource.setrlimit(resource.RLIMIT_CPU, (math.ceil(seconds), math.ceil(seconds) + 1))
    from mobot_cli import plan_json
    from mobot_cli.assets import sandbox
    from mobot_cli.assets.resources import ResourceResolver
    from mobot_cli.common.cache import cache_dir
    from mobot_cli.scenario.prepare import prepare

    roots = [folder, *ResourceResolver(folder).roots]
    package = str(Path(_PACKAGE_PARENT) / "mobot_cli")  # its own lazy imports: that folder, not its parent
    readable = [*roots, cache_dir(), package, *(p for p in sys.path[1:] if p), sys.prefix, sys.base_prefix]
    refusals = _guard_opens([str(Path(p).resolve()) for p in readable])
    try:
        with sandbox.confined(roots):
            plan, error = prepare(folder / "scenario.yaml").plan, None
    except MobotError as exc:
        refused = refusals or _refused(exc, (sandbox.OutsideRoots, sandbox.Forbidden, sandbox.LimitExceeded))
        plan, error = None, ("Refused" if refused else type(exc).__name__, str(exc))
    except MemoryError:
        plan, error = None, ("LimitExceeded", f"it needs more than {memory >> 20} MiB of memory")
    except RecursionError:
        plan, error = None, ("LimitExceeded", "it nests too deeply to load")
    except Exception as exc:  # noqa: BLE001 - whatever a damaged file trips in a loader is this folder's fault
        plan, error = None, ("Refused" if isinstance(exc, PermissionError) else type(exc).__name__,
                             f"{type(exc).__name__}: {exc}")
    try:
        reply = plan_json.dump((plan, error and (error[0], _utf8(error[1]))))
    except ValueError as exc:  # a file name that is not UTF-8 in the plan: JSON has no such text
        reply = plan_json.dump((None, ("ValueError", f"its plan cannot be written as JSON: {exc}")))
    out.write(reply)
    out.close()
    return 0


def _utf8(text: str) -> str:
    """``text`` with what is not UTF-8 (a file name's undecodable bytes) as backslash escapes."""
    return text.encode("utf-8", "backslashreplace").decode("utf-8")


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
