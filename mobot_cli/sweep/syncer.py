"""Run folders' summary.json flushed to disk by the sweep, off the workers' clocks.

`mobot run` flushes summary.json itself (an fsync, which holds the run up). A sweep's workers write it
without, and the sweep flushes each one from a thread as its run is reported, while the next
runs go on; the sweep waits for the last ones before it writes its final results.csv and
sweep.json. So, as with `mobot run`, a finished sweep's summaries are on disk; a power cut in
the middle may lose the last ones, as it may lose the last rows of results.csv.
"""

from __future__ import annotations

import os
import queue
import threading
from pathlib import Path

_DONE = None


class Syncer:
    """A thread that fsyncs the files it is given; ``close`` waits for them and raises the
    first OSError met (a file that vanished is not one: its run failed before writing it)."""

    def __init__(self) -> None:
        self._queue: queue.SimpleQueue[Path | None] = queue.SimpleQueue()
        self.error: OSError | None = None
        self._thread = threading.Thread(target=self._work, name="mobot-sweep-fsync", daemon=True)
        self._thread.start()

    def add(self, path: Path) -> None:
        """Flush ``path`` to disk soon."""
        self._queue.put(path)

    def close(self) -> None:
        """Wait until every file given is flushed; raise the first failure."""
        if self._thread.is_alive():
            self._queue.put(_DONE)
            self._thread.join()
        if self.error is not None:
            raise self.error

    def _work(self) -> None:
        while (path := self._queue.get()) is not _DONE:
            try:
                fd = os.open(path, os.O_RDONLY)
            except FileNotFoundError:
                continue
            except OSError as exc:
                self.error = self.error or exc
                continue
            try:
                os.fsync(fd)
            except OSError as exc:
                exc.filename = str(path)
                self.error = self.error or exc
            finally:
                os.close(fd)
