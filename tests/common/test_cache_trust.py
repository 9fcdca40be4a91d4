"""The cache as an attacker finds it: someone else's or a shared folder, planted links and FIFOs,
forged entries, a read-only or full disk. Every run still ends 0 with its outputs and at most one
warning, and nothing outside the cache is touched (issue 26, docs/security.md)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from mobot_cli.common import cache

REPO = Path(__file__).resolve().parents[2]
QUICKSTART = REPO / "scenarios" / "quickstart.yaml"
NOBODY = 65534  # another user: the attacker's files are chown'ed to it


def run(cache_dir: Path, out: Path) -> subprocess.CompletedProcess:
    """`mobot run quickstart` with this cache, bounded: a hang fails the test, never blocks it."""
    env = {**os.environ, "MOBOT_CACHE_DIR": str(cache_dir)}
    done = subprocess.run([sys.executable, "-m", "mobot_cli", "run", str(QUICKSTART), "--out", str(out)],
                          env=env, capture_output=True, text=True, timeout=600)
    assert "Traceback" not in done.stderr, done.stderr
    assert done.returncode == 0, done.stderr
    assert json.loads((out / "summary.json").read_text())["status"] == "ok"
    return done


def warnings(done: subprocess.CompletedProcess) -> list[str]:
    return [line for line in done.stderr.splitlines() if "cache folder" in line]


@pytest.fixture
def fresh(monkeypatch, tmp_path):
    """A cache path of this test's own; the per-process verdict is forgotten before and after."""
    cache._checked.cache_clear()
    yield tmp_path
    cache._checked.cache_clear()


def mount_tmpfs(where: Path, options: str) -> None:
    where.mkdir()
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(where)], capture_output=True)
    if done.returncode:
        pytest.skip(f"cannot mount a tmpfs here: {done.stderr.decode().strip()}")


def test_a_new_cache_folder_is_private_and_a_warm_run_uses_it(fresh):
    first = run(fresh / "c", fresh / "o1")
    assert warnings(first) == []
    assert (fresh / "c").stat().st_mode & 0o777 == 0o700
    assert all(p.stat().st_mode & 0o077 == 0 for p in (fresh / "c").iterdir())
    entries = sorted(p.relative_to(fresh / "c") for p in (fresh / "c").rglob("*") if p.is_file())
    assert len(entries) >= 3  # robot, world, urdf at least
    run(fresh / "c", fresh / "o2")
    assert sorted(p.relative_to(fresh / "c") for p in (fresh / "c").rglob("*") if p.is_file()) == entries


@pytest.mark.parametrize("how", ["other-writable", "group-writable", "another user's", "a link", "in a shared parent"])
def test_a_folder_others_can_change_turns_caching_off_with_one_warning(fresh, how):
    folder = fresh / "c"
    folder.mkdir(mode=0o700)
    if how == "other-writable":
        folder.chmod(0o777)
    elif how == "group-writable":
        folder.chmod(0o770)
    elif how == "another user's":
        os.chown(folder, NOBODY, NOBODY)
    elif how == "a link":
        (fresh / "link").symlink_to(folder)
        folder = fresh / "link"
    else:
        shared = fresh / "shared"
        shared.mkdir()
        shared.chmod(0o777)  # writable by all, no sticky bit: anyone may rename our folder away
        folder = shared / "c"
        folder.mkdir(mode=0o700)
    planted = folder / "robot"
    planted.mkdir(exist_ok=True)
    before = sorted(os.listdir(folder))
    done = run(folder, fresh / "out")
    assert len(warnings(done)) == 1, done.stderr
    assert "caching is off" in warnings(done)[0]
    assert sorted(os.listdir(folder)) == before and os.listdir(planted) == []  # nothing read or written


def test_a_sticky_shared_parent_is_fine_when_the_folder_is_ours(fresh):
    shared = fresh / "tmp"
    shared.mkdir()
    shared.chmod(0o1777)
    done = run(shared / "c", fresh / "out")
    assert warnings(done) == []
    assert any((shared / "c").rglob("*.json"))


def test_forged_entries_are_misses(fresh, monkeypatch):
    monkeypatch.setenv("MOBOT_CACHE_DIR", str(fresh / "c"))
    key = cache.digest("robot", "a robot")
    cache.store("robot", key, {"text": "mine"})
    entry = fresh / "c" / "robot" / f"{key}.json"
    good = entry.read_bytes()
    entry.write_bytes(good.replace(b"mine", b"evil"))  # edited body: its hash no longer matches
    assert cache.load("robot", key) is None
    other = cache.digest("robot", "another robot")
    (entry.parent / f"{other}.json").write_bytes(good)  # a good entry under another key
    assert cache.load("robot", other) is None
    entry.write_bytes(good)
    assert cache.load("robot", key) == {"text": "mine"}
    os.chown(entry, NOBODY, NOBODY)  # a valid entry, but another user's file
    assert cache.load("robot", key) is None
    text = "<robot name='r'/>"
    from mobot_cli.sim.bullet.urdf_file import urdf_path

    path = urdf_path(text)
    path.write_text("<robot name='forged'/>")
    again = urdf_path(text)  # its name is its hash: a changed file is rewritten
    assert again.read_text() == text


def test_links_planted_where_files_go_and_where_cleanup_looks_touch_nothing_outside(fresh, monkeypatch):
    monkeypatch.setenv("MOBOT_CACHE_DIR", str(fresh / "c"))
    victim = fresh / "home"
    victim.mkdir()
    for i in range(77):
        (victim / f"file{i}.txt").write_text(f"precious {i}")
    from mobot_cli.sim.bullet.urdf_file import urdf_path

    text = "<robot name='r'/>"
    path = urdf_path(text)
    path.unlink()
    path.symlink_to(victim / "file0.txt")  # where the next write goes
    assert urdf_path(text).read_text() == text and not path.is_symlink()
    for i in range(1, 40):
        (fresh / "c" / "urdf" / f"link{i}.urdf").symlink_to(victim / f"file{i}.txt")
    assert cache.prune(fresh / "c" / "urdf", max_files=1, max_bytes=1) == 0  # only the links beside it
    (fresh / "c" / "xacro").symlink_to(victim, target_is_directory=True)  # a whole kind folder
    for i in range(30):
        cache.store("xacro", cache.digest("x", str(i)), {"i": i})
    assert cache.prune(fresh / "c" / "xacro", max_files=1) == 0
    assert sorted(os.listdir(victim)) == sorted(f"file{i}.txt" for i in range(77))
    assert all((victim / f"file{i}.txt").read_text() == f"precious {i}" for i in range(77))


def test_fifos_and_devices_in_the_cache_are_misses_never_hangs(fresh):
    run(fresh / "c", fresh / "o1")
    files = [p for p in (fresh / "c").rglob("*") if p.is_file()]
    for path in files:
        path.unlink()
        os.mkfifo(path)
    done = run(fresh / "c", fresh / "o2")  # bounded by run()'s timeout
    assert warnings(done) == []
    assert all(p.is_file() for p in files)  # each miss was written again, replacing the FIFO


@pytest.mark.parametrize("fault", ["a file", "read-only", "full"])
def test_a_cache_that_cannot_be_written_only_costs_time(fresh, fault):
    if fault == "a file":
        folder = fresh / "c"
        folder.write_text("not a folder")
    elif fault == "read-only":
        mount_tmpfs(fresh / "mnt", "ro,size=1m,mode=0700")
        folder = fresh / "mnt"
    else:
        mount_tmpfs(fresh / "mnt", "size=8k,mode=0700")
        folder = fresh / "mnt"
    try:
        done = run(folder, fresh / "out")
        if fault == "a file":
            assert len(warnings(done)) == 1 and "not a folder" in warnings(done)[0]
        else:
            assert len(warnings(done)) == 0  # a private folder whose writes fail: silent misses
    finally:
        if fault != "a file":
            subprocess.run(["umount", str(fresh / "mnt")], check=False)


def test_a_sweep_warns_once_not_per_run(fresh):
    shared = fresh / "shared"
    shared.mkdir()
    shared.chmod(0o777)
    env = {**os.environ, "MOBOT_CACHE_DIR": str(shared)}
    sweep = REPO / "scenarios" / "sweeps" / "engines.yaml"
    done = subprocess.run([sys.executable, "-m", "mobot_cli", "sweep", str(sweep), "--out", str(fresh / "sweep")],
                          env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0 and "Traceback" not in done.stderr, done.stderr
    assert len(warnings(done)) == 1, done.stderr
    assert os.listdir(shared) == []
