"""A helper process forked as `mobot run` starts, so that a second core shares the run's fixed cost.

The entry point forks it before the CLI is imported (``fork_helper``). While this process reads
the scenario file (PyYAML, --set) and imports the CLI and the engine (numpy, PyBullet, the
timeline and its sinks), the helper imports what validates a scenario (pydantic, the scenario
models); given the document read, it validates and resolves it and sends the plan and the
resolved document back (this process writes it as YAML), with the file PyBullet loads each URDF
from and the links whose friction it sets (sim/urdf_file.py), which this process then need not
work out. It then loads the drawing code (run/picture.py: Pillow and fonts, not the engine),
makes ready the memory a picture takes (common/heap.py) and waits: at the run's end it draws
trajectory.png from the tracks this process sends it.

The helper only saves time. Whenever it cannot help (no second core, no fork, a scenario it
could not prepare, a picture it could not write, a helper that died), this process does the
same work itself, so the files, messages and exit codes are the same either way: an error is
always reported by the code that reports it without the helper. It prints nothing, never
touches the terminal and ignores Ctrl-C, which is this process's to handle. MOBOT_HELPER=0
turns it off.
"""

from __future__ import annotations

import os
import pickle
import signal
import struct
from pathlib import Path

_LENGTH = struct.Struct("<Q")
_forked: "Ahead | None" = None  # forked by the entry point, not yet taken by a run


class Ahead:
    """This process's end of the helper: its pid and the two pipes to it."""

    def __init__(self, pid: int, reader: int, writer: int):
        self.pid: int | None = pid
        self.reader, self.writer = reader, writer
        self.painting: Path | None = None  # the picture it draws now

    def prepare(self, source) -> None:
        """Ask the helper to validate and resolve ``source``, a scenario.source.Source this process
        read and made ready (scenario/overrides.read_ready); ``prepared`` takes the answer."""
        try:
            _send(self.writer, source)
        except OSError:  # it is gone: prepared() says None
            pass

    def prepared(self):
        """(plan, resolved document) from the helper; None: prepare here (and report its error).
        The URDF facts it sent with them are this process's from now on (sim/urdf_file.py)."""
        try:
            answer = _receive(self.reader)
        except OSError:
            return None
        if answer is None:
            return None
        plan, document, facts = answer
        from mobot_cli.sim.urdf_file import known

        known(facts)
        return plan, document

    def paint(self, tracks: list, out: Path, title: str, subtitle: str) -> bool:
        """Have the helper draw trajectory.png (run.trajectory.Painter); False: draw it here."""
        try:
            _send(self.writer, (tracks, out, title, subtitle))
        except OSError:  # the helper is gone
            return False
        self.painting = out
        return True

    def painted(self) -> bool:
        """Wait for the picture the helper draws; False: draw it here."""
        try:
            done = _receive(self.reader) is True
        except OSError:
            done = False
        self.painting = None
        return done

    def close(self) -> None:
        """Stop the helper (whatever it is doing) and reap it."""
        if self.pid is None:
            return
        for fd in (self.reader, self.writer):
            os.close(fd)
        try:
            os.kill(self.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        try:
            os.waitpid(self.pid, 0)
        except ChildProcessError:  # reaped already (SIGCHLD ignored)
            pass
        if self.painting is not None:  # stopped while it drew (Ctrl-C): no half a picture left
            from mobot_cli.common.files import remove_temporaries  # not before the fork: it is early

            remove_temporaries(self.painting, self.pid)
        self.pid = None


def fork_helper() -> None:
    """Fork the helper now, where it can help (two cores, os.fork, not MOBOT_HELPER=0).

    Called by the entry point before anything else is imported, so no thread is running yet."""
    global _forked
    if os.environ.get("MOBOT_HELPER", "1") == "0" or not hasattr(os, "fork") or _cores() < 2:
        return
    try:
        down_r, down_w = os.pipe()  # this process -> helper
        up_r, up_w = os.pipe()  # helper -> this process
        pid = os.fork()
    except OSError:  # out of processes or descriptors: run without it
        return
    if pid == 0:  # the helper: it never returns into the CLI
        try:
            signal.signal(signal.SIGINT, signal.SIG_IGN)
            _quiet()
            from mobot_cli.common.forked import close_fds_but

            close_fds_but({0, 1, 2, down_r, up_w})
            _helper(down_r, up_w)
        finally:
            os._exit(0)
    os.close(down_r)
    os.close(up_w)
    _forked = Ahead(pid, up_r, down_w)


def take() -> Ahead | None:
    """The helper the entry point forked, once; None without one (invoke(), tests, MOBOT_HELPER=0)."""
    global _forked
    ahead, _forked = _forked, None
    return ahead


def _cores() -> int:
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def _quiet() -> None:
    """Stdin, stdout and stderr to /dev/null: the parent says all there is to say, and a caller
    reading the parent's output to its end must not wait for the helper."""
    devnull = os.open(os.devnull, os.O_RDWR)
    for fd in (0, 1, 2):
        os.dup2(devnull, fd)
    os.close(devnull)


def _helper(reader: int, writer: int) -> None:
    """The helper's life: import, prepare when told what, send the plan, load the drawing code,
    draw when asked."""
    try:
        from mobot_cli.run.prepare import resolve_ready
    except BaseException:
        return
    source = _receive(reader)
    if source is None:
        return
    try:
        _, plan, document = resolve_ready(source)
    except BaseException:
        _send(writer, None)  # the parent prepares it again and reports what is wrong
        return
    from mobot_cli.sim.urdf_file import facts

    _send(writer, (plan, document, facts(_urdf_texts(plan))))
    from mobot_cli.common.classcode import save
    from mobot_cli.run.picture import draw, preload

    preload(one_picture=True)  # while the run's loop goes on
    save()  # the classes made here that the run did not make (it saves its own at exit)
    request = _receive(reader)
    if request is None:
        return
    tracks, out, title, subtitle = request
    try:
        draw(tracks, plan.world, out, title, subtitle)  # atomic: nothing half-written is left
    except BaseException:
        _send(writer, False)  # the parent draws it again and reports what is wrong
        return
    _send(writer, True)


def _urdf_texts(plan) -> list[str]:
    """The URDF texts the run loads: its robots' and its world's static bodies made of one."""
    return [*dict.fromkeys(robot.urdf for robot in plan.robots),
            *(body.urdf for body in plan.world.bodies if body.urdf and not body.shapes)]


def _send(fd: int, value: object) -> None:
    data = pickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL)
    view = memoryview(_LENGTH.pack(len(data)) + data)
    while view:
        view = view[os.write(fd, view):]


def _receive(fd: int) -> object:
    """The next value; None when the other end closed first."""
    head = _read(fd, _LENGTH.size)
    if head is None:
        return None
    data = _read(fd, _LENGTH.unpack(head)[0])
    return None if data is None else pickle.loads(data)


def _read(fd: int, size: int) -> bytes | None:
    parts, left = [], size
    while left:
        chunk = os.read(fd, min(left, 1 << 20))
        if not chunk:
            return None
        parts.append(chunk)
        left -= len(chunk)
    return b"".join(parts)
