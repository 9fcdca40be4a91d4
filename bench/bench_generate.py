#!/usr/bin/env python3
"""Generating worlds (`world: {generate: ...}`): CPU per world, best and median over seeds.

* the generator alone (obstacles from the seed: for barn the cellular automaton, its smoothing
  and the free-way check), and with the SDF text and the WorldPlan the run needs (what
  `mobot run` spends on the world); goal for a BARN-like world: <= 50 ms
* beside it, loading the same world from its SDF file (cold: lxml, no cache), as a world file

    python3 bench/bench_generate.py [--seeds 30]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

CASES = (("barn", {"fill": 0.15}), ("barn", {"fill": 0.3}), ("boxes", {"count": 40}),
         ("maze", {"cells": (10, 10)}), ("rooms", {"rooms": (4, 3)}))


def cpu(fn) -> float:
    started = time.process_time()
    fn()
    return time.process_time() - started


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=30)
    args = parser.parse_args()
    from mobot_cli.assets.resources import ResourceResolver
    from mobot_cli.assets.world.build import build_world
    from mobot_cli.assets.world.generate.make import generate, load_generated

    load_generated("barn", 0, {})  # imports
    print(f"{'world':<24}{'obstacles':>10}{'generate ms':>14}{'+ SDF + plan ms':>18}{'load SDF ms':>14}")
    for kind, params in CASES:
        gen, full, load, count = [], [], [], 0
        for seed in range(args.seeds):
            gen.append(cpu(lambda: generate(kind, seed, params)))
            full.append(cpu(lambda: load_generated(kind, seed, params)))
            count = len(generate(kind, seed, params).obstacles)
            if seed < 5:  # the cold SDF path is slow: a few seeds will do
                with tempfile.TemporaryDirectory() as folder:
                    path = Path(folder) / "generated.world"
                    path.write_text(load_generated(kind, seed, params)[1], encoding="utf-8")
                    load.append(cpu(lambda: build_world(path, ResourceResolver(None), False)))
        label = f"{kind} {','.join(f'{k}={v}' for k, v in params.items())}"
        print(f"{label:<24}{count:>10}{_ms(gen):>14}{_ms(full):>18}{_ms(load):>14}")
    print("(CPU ms, best / median over the seeds)")


def _ms(values: list[float]) -> str:
    return f"{min(values) * 1000:.1f} / {statistics.median(values) * 1000:.1f}"


if __name__ == "__main__":
    main()
