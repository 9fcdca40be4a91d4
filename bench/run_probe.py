#!/usr/bin/env python3
"""`mobot` run as its console script runs it, with the run's own loop timed inside it, for
bench_run.py: mobot's fixed cost is then the whole process minus its own loop, measured as
raw_run.py measures the raw script's (whose loop writes its CSV rows, as mobot's writes its).

    python3 bench/run_probe.py run SCENARIO --out DIR --quiet   # the loop's wall seconds, last on stderr

Nothing of mobot is imported before its entry point runs: an import hook wraps
``mobot_cli.run.execute._play`` (from the first step after the spawn to the last tick, every
sink writing) when the run imports that module, so the start-up being measured is the real one.
"""

from __future__ import annotations

import importlib.abc
import importlib.machinery
import os
import sys
import time

TARGET = "mobot_cli.run.execute"


class _TimePlay(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path, target=None):
        if name != TARGET:
            return None
        sys.meta_path.remove(self)
        spec = importlib.machinery.PathFinder.find_spec(name, path)
        load = spec.loader.exec_module

        def exec_module(module):
            load(module)
            play = module._play

            def timed(*args, **kwargs):
                started = time.perf_counter()
                try:
                    return play(*args, **kwargs)
                finally:
                    os.write(2, f"\n{time.perf_counter() - started:.6f}\n".encode())

            module._play = timed

        spec.loader.exec_module = exec_module
        return spec


if __name__ == "__main__":
    sys.meta_path.insert(0, _TimePlay())
    sys.argv = ["mobot", *sys.argv[1:]]
    from mobot_cli.__main__ import entry

    entry()
