"""Dataclass methods and forward references kept compiled in the cache folder (common/classcode.py):
classes and type hints made from the kept code are those Python makes, a second process compiles
nothing, and a cache file is only trusted when this user wrote it. Each case runs in a process of
its own: install() changes how that whole process makes them."""

from __future__ import annotations

import json
import marshal
import os
import subprocess
import sys
from pathlib import Path

import pytest

from mobot_cli.common import classcode

REPO = Path(__file__).resolve().parents[2]
# Makes dataclasses of every kind with the cache installed (argv[1] == "1") or not, and prints what
# they do and how their methods were had.
PROBE = r"""
import dataclasses, json, sys
from mobot_cli.common import classcode
if sys.argv[1] == "1":
    classcode.install()
from dataclasses import dataclass, field, replace, FrozenInstanceError, KW_ONLY
from typing import ForwardRef, TypedDict, get_type_hints

@dataclass(frozen=True)
class Pose:
    x: float
    y: float = 0.0
    tags: tuple = ()

@dataclass(order=True)
class Track:
    name: str
    points: list = field(default_factory=list)
    note: str = field(default="", compare=False, repr=False)
    _: KW_ONLY
    rate: int = 48

@dataclass(slots=True, kw_only=True)
class Slot:
    a: int
    b: "list[int]" = field(default_factory=lambda: [1, 2])

class Row(TypedDict, total=False):
    name: "str"
    points: "list[tuple[float, float]] | None"

def scale(pose: "Pose", by: "dict[str, float] | None" = None) -> "Pose":
    return pose

refs = [ForwardRef("dict[str, int] | None"), ForwardRef("Pose")]
p, q = Pose(1.0, tags=("a",)), Track("t", [(0, 1)], note="n", rate=10)
try:
    p.x = 3
    frozen = "no"
except FrozenInstanceError:
    frozen = "yes"
out = {
    "repr": [repr(p), repr(q), repr(Slot(a=1))],
    "eq": [p == Pose(1.0, 0.0, ("a",)), q == Track("t", [(0, 1)], note="other", rate=10), Track("a") < Track("b")],
    "hash": hash(p) == hash(Pose(1.0, tags=("a",))),
    "frozen": frozen,
    "replace": repr(replace(p, y=2.0)),
    "slots": Slot.__slots__,
    "init": [[c.__init__.__code__.co_code.hex(), c.__init__.__code__.co_varnames, repr(c.__init__.__code__.co_consts),
              str(c.__init__.__annotations__)] for c in (Pose, Track, Slot)],
    "refs": [[r.__forward_code__.co_code.hex(), r.__forward_code__.co_names] for r in refs],
    "hints": [str(get_type_hints(Row)), str(get_type_hints(scale))],
    "fresh": classcode._fresh,
    "kept": len(classcode._codes),
}
print(json.dumps(out))
"""


def _probe(cache: Path, installed: bool) -> dict:
    done = subprocess.run([sys.executable, "-c", PROBE, "1" if installed else "0"], capture_output=True, text=True,
                          env={**os.environ, "MOBOT_CACHE_DIR": str(cache)}, cwd=REPO, check=True)
    return json.loads(done.stdout)


def _kept(cache: Path) -> Path:
    return cache / classcode.KIND / f"{classcode._TAG}.marshal"


def test_classes_from_kept_code_are_the_classes_python_makes(tmp_path):
    plain = _probe(tmp_path, installed=False)
    first = _probe(tmp_path, installed=True)  # compiles, and keeps what it compiled at exit
    assert first["fresh"] is True and _kept(tmp_path).stat().st_size > 1000
    again = _probe(tmp_path, installed=True)
    assert again["fresh"] is False  # every method from the cache
    for made in (first, again):
        assert {k: v for k, v in made.items() if k not in ("fresh", "kept")} == \
               {k: v for k, v in plain.items() if k not in ("fresh", "kept")}
    assert plain["eq"] == [True, True, True] and plain["frozen"] == "yes"
    assert plain["repr"][1] == "Track(name='t', points=[(0, 1)], rate=10)"


def test_a_second_mobot_run_compiles_no_dataclass_method(tmp_path):
    """The texts are the same from process to process: a second run leaves the kept file as it was."""
    scenario = REPO / "scenarios" / "quickstart.yaml"
    env = {**os.environ, "MOBOT_CACHE_DIR": str(tmp_path / "cache")}
    for i in range(2):
        subprocess.run([sys.executable, "-m", "mobot_cli", "run", str(scenario), "--quiet", "--out",
                        str(tmp_path / f"run{i}")], check=True, env=env, cwd=REPO)
        if i == 0:
            kept = _kept(tmp_path / "cache")
            before = (kept.stat().st_mtime_ns, kept.read_bytes())
            codes = marshal.loads(before[1])
            # the run's own plan types and the helper's (pydantic's, made only where it validates)
            assert any("def __init__(self,rate_hz:" in text for text in codes)
            assert len(codes) > 100
    assert (kept.stat().st_mtime_ns, kept.read_bytes()) == before
    assert _files(tmp_path / "run0") == _files(tmp_path / "run1")


@pytest.mark.parametrize("spoil", ["group-writable", "link", "damaged", "not code"])
def test_a_file_not_to_be_trusted_is_not_read_and_is_replaced(tmp_path, spoil):
    _probe(tmp_path, installed=True)
    kept = _kept(tmp_path)
    codes = marshal.loads(kept.read_bytes())
    # Every text runs code that would mark the probe's classes: trusted, it would show.
    evil = compile("raise SystemExit('ran the cache')", "<string>", "exec")
    if spoil == "group-writable":
        kept.write_bytes(marshal.dumps({text: evil for text in codes}))
        kept.chmod(0o664)
    elif spoil == "link":
        other = tmp_path / "elsewhere.marshal"
        other.write_bytes(marshal.dumps({text: evil for text in codes}))
        other.chmod(0o644)
        kept.unlink()
        kept.symlink_to(other)
    elif spoil == "damaged":
        kept.write_bytes(kept.read_bytes()[: len(kept.read_bytes()) // 2])
    else:
        kept.write_bytes(marshal.dumps({text: "print('hello')" for text in codes}))
    made = _probe(tmp_path, installed=True)
    assert made["fresh"] is True  # compiled anew, not run from that file
    if spoil != "link":
        assert marshal.loads(kept.read_bytes()).keys() == codes.keys()  # and kept again, whole
        assert all(type(code) is type(evil) for code in marshal.loads(kept.read_bytes()).values())


def test_a_full_cache_keeps_what_its_last_process_used(tmp_path, monkeypatch):
    kept = _kept(tmp_path)
    kept.parent.mkdir(parents=True)
    old = {f"x = {i}": compile(f"x = {i}", "<string>", "exec") for i in range(classcode.MAX_ENTRIES)}
    kept.write_bytes(marshal.dumps(old))
    kept.chmod(0o644)
    made = _probe(tmp_path, installed=True)
    codes = marshal.loads(kept.read_bytes())
    assert made["fresh"] is True and 0 < len(codes) < 100  # the probe's methods, not the 2,048 others
    assert not any(text.startswith("x = ") for text in codes)
    assert _probe(tmp_path, installed=True)["fresh"] is False


def test_no_cache_folder_costs_nothing_but_the_time(tmp_path):
    blocked = tmp_path / "file"
    blocked.write_text("a file where the cache folder would be")
    made = _probe(blocked, installed=True)
    assert made["fresh"] is True and made["eq"] == [True, True, True]


def _files(run: Path) -> dict:
    """A run folder's files but summary.json (whose wall time differs), by their path in it."""
    return {str(p.relative_to(run)): p.read_bytes() for p in sorted(run.rglob("*"))
            if p.is_file() and p.name != "summary.json"}
