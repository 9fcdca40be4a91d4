#!/usr/bin/env python3
"""Thousands of mutated bundled scenarios and sweep files through load + resolve; counts printed.

The property of tests/test_scenario_fuzz.py at scale: every mutated file (and --set value)
is accepted or refused with a one-paragraph MobotError naming the file, in bounded time. A
"traceback" is anything else; each is saved under --keep for replaying with `mobot check`.

    python3 bench/fuzz_scenarios.py [--examples 1200] [--seed 1] [--keep DIR]
"""

from __future__ import annotations

import argparse
import collections
import os
import sys
import tempfile
import time
import traceback
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(REPO)]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--examples", type=int, default=1200, help="mutated inputs in all (>= 1000 for the report)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--keep", type=Path, default=Path("fuzz-failures"), help="where failing inputs are saved")
    args = parser.parse_args()
    os.environ.setdefault("MOBOT_CACHE_DIR", tempfile.mkdtemp(prefix="mobot-fuzz-cache-"))

    from hypothesis import Phase, given, seed, settings
    from hypothesis import strategies as st

    from tests.scenario.mutations import BUNDLED, check, mutated, override, workspace

    counts: collections.Counter[str] = collections.Counter()
    slowest = [0.0, ""]
    root = workspace(Path(tempfile.mkdtemp(prefix="mobot-fuzz-")))
    per_file = max(1, args.examples // len(BUNDLED))

    for original in BUNDLED:
        relative = original.relative_to(REPO / "scenarios")
        path = (root / relative).with_name("mutated-" + original.name)

        def one(kind: str, target: Path, overrides: list[str], given_input: bytes) -> None:
            started = time.perf_counter()
            try:
                counts[kind, check(target, overrides)] += 1
            except Exception:  # noqa: BLE001 - the bench counts what the property forbids
                counts[kind, "tracebacks"] += 1
                keep = args.keep / f"{original.stem}-{sum(counts.values())}"
                keep.mkdir(parents=True, exist_ok=True)
                (keep / ("input.yaml" if kind == "file" else "set.txt")).write_bytes(given_input)
                (keep / "traceback.txt").write_text(traceback.format_exc())
            took = time.perf_counter() - started
            if took > slowest[0]:
                slowest[:] = [took, f"{relative} ({kind})"]

        @seed(args.seed)
        @settings(max_examples=per_file * 3 // 4, deadline=None, database=None, phases=[Phase.generate])
        @given(data=st.data())
        def files(data) -> None:
            text = data.draw(mutated(original))
            path.write_bytes(text)
            one("file", path, [], text)

        @seed(args.seed)
        @settings(max_examples=per_file - per_file * 3 // 4, deadline=None, database=None, phases=[Phase.generate])
        @given(data=st.data())
        def sets(data) -> None:
            item = data.draw(override(original))
            one("--set", root / relative, [item], item.encode("utf-8", "surrogateescape"))

        files()
        sets()

    total = sum(counts.values())
    refused = sum(n for (_, outcome), n in counts.items() if outcome == "refused")
    accepted = sum(n for (_, outcome), n in counts.items() if outcome == "accepted")
    broken = sum(n for (_, outcome), n in counts.items() if outcome == "tracebacks")
    print(f"examples={total} accepted={accepted} refused={refused} tracebacks={broken} "
          f"slowest={slowest[0]:.2f}s ({slowest[1]})")
    for (kind, outcome), n in sorted(counts.items()):
        print(f"  {kind:6} {outcome:10} {n}")
    if broken:
        print(f"failing inputs and tracebacks: {args.keep}/")
    return 1 if broken else 0


if __name__ == "__main__":
    sys.exit(main())
