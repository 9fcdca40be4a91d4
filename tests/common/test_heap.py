"""common/heap.py: memory made ready ahead is reused without page faults (in a process of its own,
as it changes how that process's allocator works for the rest of its life)."""

from __future__ import annotations

import json
import platform
import subprocess
import sys

import pytest

PROBE = """
import json, resource, sys
from mobot_cli.common.heap import reserve
reserved = reserve({reserve}) if {reserve} else None
def faults():
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt
before = faults()
canvas = bytearray(17 << 20)  # about a picture's canvas, zero-filled: every page touched
rows = bytearray(3 << 20)
print(json.dumps({{"reserved": reserved, "faults": faults() - before}}))
"""


def _probe(reserve: int) -> dict:
    out = subprocess.run([sys.executable, "-c", PROBE.format(reserve=reserve)], capture_output=True, text=True,
                         check=True).stdout
    return json.loads(out)


@pytest.mark.skipif(platform.system() != "Linux" or platform.libc_ver()[0] != "glibc",
                    reason="mallopt is glibc's; elsewhere reserve() does nothing and says so")
def test_reserved_memory_is_reused_without_faulting_its_pages_in_again():
    cold, warm = _probe(0), _probe(32 << 20)
    assert cold["faults"] > (20 << 20) // 4096 * 0.9  # each 4 KiB page of the 20 MiB, the first time
    assert warm["reserved"] is True
    assert warm["faults"] < cold["faults"] / 10


def test_the_picture_memory_covers_what_a_picture_allocates():
    from mobot_cli.plot.render import HEIGHT, MEMORY, SS, WIDTH

    canvas, reduced, rows = 4 * WIDTH * SS * HEIGHT * SS, 4 * WIDTH * HEIGHT, 3 * WIDTH * HEIGHT
    assert canvas + reduced + 2 * rows < MEMORY < 2 * (canvas + reduced + 2 * rows)
