"""A sweep's folder and workers are its own: one sweep per folder, no worker outliving its sweep.

* ``FolderLock``: ``DIR/.lock``, held (``flock``) by the sweep running in DIR for as long as it
  runs, so that a ``--resume`` cannot race a live sweep in the same run folders. The kernel
  drops the lock when the process ends, however it ends: a stale lock file means nothing.
* ``die_with_sweep``: a worker asks the kernel for SIGKILL when its parent dies (Linux
  ``PR_SET_PDEATHSIG``; the parent is the sweep, or the fork server, which leaves when the
  sweep does), and a watchdog thread checks the same, so that ``kill -9`` of a sweep does not
  leave its runs going on.
"""

from __future__ import annotations

import ctypes
import fcntl
import os
import select
import signal
import threading
from pathlib import Path

from mobot_cli.errors import UsageError, cannot_write

LOCK_FILE = ".lock"
WATCH_S = 0.5  # how often the watchdog looks when the kernel cannot tell it
_PR_SET_PDEATHSIG = 1


class FolderLock:
    """An exclusive lock on ``folder/.lock`` for one sweep; ``UsageError`` when another holds it."""

    def __init__(self, folder: Path):
        self.path = folder / LOCK_FILE
        self._fd: int | None = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
        try:
            fcntl.flock(self._fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = _read_pid(self._fd)
            self.release()
            who = f"a sweep (pid {holder})" if holder else "another sweep"
            raise UsageError(f"{who} is still running in {folder}",
                             hint="Wait for it to end or stop it, then --resume; or choose another --out.") from None
        try:  # who holds it, for the message above (a full disk must not stop the sweep here)
            os.ftruncate(self._fd, 0)
            os.write(self._fd, f"{os.getpid()}\n".encode())
        except OSError:
            pass

    def release(self) -> None:
        """Let the next sweep in (the file stays: removing it would race one that opens it)."""
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None

    def __enter__(self) -> "FolderLock":
        return self

    def __exit__(self, *exc) -> None:
        self.release()


def check_unlocked(folder: Path) -> None:
    """UsageError when a live sweep holds ``folder``'s lock (checked before reading its files)."""
    if (folder / LOCK_FILE).is_file():
        try:
            FolderLock(folder).release()
        except OSError as exc:
            raise cannot_write(folder / LOCK_FILE, exc) from None


def _read_pid(fd: int) -> int | None:
    try:
        text = os.pread(fd, 32, 0).decode().strip()
    except (OSError, UnicodeDecodeError):
        return None
    return int(text) if text.isdigit() else None


def die_with_sweep(sweep_pid: int) -> None:
    """Make this worker process end (SIGKILL) as soon as its sweep ends, even by SIGKILL."""
    parent = os.getppid()
    _parent_death_signal(signal.SIGKILL)
    if os.getppid() != parent:  # the parent died before the kernel was asked
        os.kill(os.getpid(), signal.SIGKILL)
    threading.Thread(target=_watch, args=(parent, sweep_pid), name="mobot-sweep-watchdog", daemon=True).start()


def _parent_death_signal(sig: int) -> bool:
    """Linux only: the kernel sends ``sig`` when the parent process ends."""
    try:
        # The C library this process already has (dlopen(NULL)): ctypes.util.find_library would
        # run `ldconfig -p` in a subprocess, in every worker as it starts.
        libc = ctypes.CDLL(None, use_errno=True)
        return libc.prctl(_PR_SET_PDEATHSIG, int(sig), 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


def _watch(parent: int, sweep_pid: int) -> None:
    """Wait for the sweep (a pidfd where there is one) or the parent to go, then die with it."""
    try:
        pidfd = os.pidfd_open(sweep_pid)
    except (AttributeError, OSError):
        pidfd = None
    while True:
        if pidfd is not None:
            gone = bool(select.select([pidfd], [], [], WATCH_S)[0])
        else:
            threading.Event().wait(WATCH_S)
            gone = False
        if gone or os.getppid() != parent:
            os.kill(os.getpid(), signal.SIGKILL)
