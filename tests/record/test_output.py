"""A run folder that cannot be written: a file as --out, a read-only folder, a full disk, the
file-size limit, a path too long. One message naming the file and the OS error, exit 2, no
traceback, only whole CSV rows, and a summary.json saying `error` where one can be written.

Real mechanisms: a tmpfs (read-only, or a few kilobytes) in a mount namespace of the test's
own (`unshare`), `chattr +i`, and RLIMIT_FSIZE; each test skips when its mechanism is missing.
"""

from __future__ import annotations

import errno
import json
import os
import resource
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from mobot_cli.cli import invoke

REPO = Path(__file__).resolve().parents[2]
QUICKSTART = REPO / "scenarios" / "quickstart.yaml"
NO_SPACE = "No space left on device [Errno 28]. Free some space or pick another --out."
TOO_LARGE = ("File too large [Errno 27]. The file reached the size limit of this process (ulimit -f): raise the "
             "limit, or log less (a shorter duration, a lower log.rate_hz).")


def mobot(*args, **kwargs) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "mobot_cli", *map(str, args)], capture_output=True, text=True,
                          cwd=REPO, timeout=120, **kwargs)


def _can_unshare() -> bool:
    if shutil.which("unshare") is None:
        return False
    probe = subprocess.run(["unshare", "--mount", "--map-root-user", "sh", "-c",
                            "mount -t tmpfs -o size=4k t /tmp"], capture_output=True)
    return probe.returncode == 0


needs_tmpfs = pytest.mark.skipif(not _can_unshare(), reason="no mount namespace (unshare) to mount a tmpfs in")


def on_tmpfs(options: str, mount: Path, copy: Path, *args, fill: bool = False) -> subprocess.CompletedProcess:
    """`mobot ARGS` with a tmpfs (``options``) on ``mount``, in a mount namespace of its own; what
    it wrote is copied to ``copy`` before the namespace, and the tmpfs, go away. ``fill``: a file
    takes all its space first."""
    mount.mkdir()
    script = ('mount -t tmpfs -o "$1" mobot-test "$2" || exit 99; '
              '[ -z "$FILL" ] || cat /dev/zero > "$2/fill" 2>/dev/null; '
              'shift 3; "$@"; rc=$?; cp -a "$MNT/." "$COPY"; exit $rc')
    copy.mkdir()
    return subprocess.run(["unshare", "--mount", "--map-root-user", "sh", "-c", script, "sh", options, str(mount),
                           "-", sys.executable, "-m", "mobot_cli", *map(str, args)],
                          capture_output=True, text=True, cwd=REPO, timeout=120,
                          env={**os.environ, "MNT": str(mount), "COPY": str(copy), "FILL": "1" if fill else ""})


def assert_whole_rows(csv_path: Path) -> int:
    """Every line of the CSV is a whole row ending in a newline; returns the rows after the header."""
    data = csv_path.read_bytes()
    assert data.endswith(b"\n"), data[-80:]
    lines = data.decode().splitlines()
    assert lines[0].startswith("t,cmd_linear,") and all(len(line.split(",")) == 16 for line in lines)
    return len(lines) - 1


def no_temporaries(folder: Path) -> list[Path]:
    return sorted(folder.rglob("*.tmp"))


# --out unusable from the start: refused before any work, nothing made ----------------------


def test_out_that_is_a_file_is_refused_before_the_run(tmp_path):
    out = tmp_path / "taken"
    out.write_text("keep me")
    outcome = invoke(["run", str(QUICKSTART), "--out", str(out), "--quiet"])
    assert outcome.exit_code == 2
    assert outcome.stderr == f"mobot: error: --out {out} is a file. Give --out a folder, new or existing.\n"
    assert out.read_text() == "keep me" and sorted(tmp_path.iterdir()) == [out]


def test_out_under_a_file_is_refused_before_the_run(tmp_path):
    (tmp_path / "taken").write_text("keep me")
    out = tmp_path / "taken" / "run"
    outcome = invoke(["run", str(QUICKSTART), "--out", str(out), "--quiet"])
    assert outcome.exit_code == 2
    assert outcome.stderr == (f"mobot: error: --out {out} cannot be made: {tmp_path / 'taken'} is a file. "
                                       "Give --out a folder, new or existing.\n")


def test_out_name_too_long_is_refused_before_the_run(tmp_path):
    out = tmp_path / ("x" * 300)
    outcome = invoke(["run", str(QUICKSTART), "--out", str(out), "--quiet"])
    assert outcome.exit_code == 2
    assert outcome.stderr == (f"mobot: error: cannot write {out}: File name too long [Errno 36]. Use shorter "
                                       "names (scenario, robots, namespaces) or a shorter --out path.\n")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(shutil.which("chattr") is None, reason="no chattr")
def test_an_unwritable_folder_is_refused_before_the_run(tmp_path):
    """Root ignores mode bits, not the immutable attribute: a folder nobody may write into."""
    locked = tmp_path / "locked"
    locked.mkdir()
    if subprocess.run(["chattr", "+i", str(locked)], capture_output=True).returncode != 0:
        pytest.skip("chattr +i is not supported here")
    try:
        done = mobot("run", QUICKSTART, "--out", locked / "run", "--quiet")
        assert list(locked.iterdir()) == []
    finally:
        subprocess.run(["chattr", "-i", str(locked)], check=True)
    assert done.returncode == 2
    assert done.stderr == (f"mobot: error: cannot write {locked / 'run'}: Permission denied [Errno 13]. "
                           "Pick a folder you may write to with --out.\n")


@needs_tmpfs
def test_a_read_only_file_system_is_refused_before_the_run(tmp_path):
    mount = tmp_path / "ro"
    done = on_tmpfs("ro", mount, tmp_path / "copy", "run", QUICKSTART, "--out", mount / "run", "--quiet")
    assert done.returncode == 2, done.stderr
    assert done.stderr == (f"mobot: error: cannot write {mount / 'run'}: Read-only file system [Errno 30]. "
                           "The file system is read-only: pick another --out.\n")


# the disk fills, the file-size limit is reached, a path grows too long: mid-run ---------------


@needs_tmpfs
def test_a_disk_already_full_leaves_no_run_folder(tmp_path):
    mount, copy = tmp_path / "full", tmp_path / "copy"
    done = on_tmpfs("size=8k", mount, copy, "run", QUICKSTART, "--out", mount / "run", "--quiet", fill=True)
    assert done.returncode == 2
    assert done.stderr == f"mobot: error: cannot write {mount / 'run' / 'scenario.yaml'}: {NO_SPACE}\n"
    assert sorted(p.name for p in copy.iterdir()) == ["fill"]


@needs_tmpfs
def test_a_full_disk_mid_run_stops_with_the_file_and_leaves_whole_rows(tmp_path):
    mount, copy = tmp_path / "small", tmp_path / "copy"
    done = on_tmpfs("size=40k", mount, copy, "run", QUICKSTART, "--out", mount / "run", "--quiet")
    assert done.returncode == 2
    assert done.stderr == f"mobot: error: cannot write {mount / 'run' / 'odom' / 'mobot.csv'}: {NO_SPACE}\n"
    run = copy / "run"
    rows = assert_whole_rows(run / "odom" / "mobot.csv")
    assert rows > 0 and rows % 50 == 0  # whole flushes: the torn last one was cut back
    assert no_temporaries(run) == [] and not (run / "trajectory.png").exists()
    if (run / "summary.json").exists():  # only when the cut freed room for it
        summary = json.loads((run / "summary.json").read_text())
        assert summary["status"] == "error" and NO_SPACE in summary["error"]


@needs_tmpfs
def test_a_full_disk_while_writing_the_bag_leaves_a_bag_that_check_can_repair(tmp_path):
    scenario = tmp_path / "bag.yaml"
    scenario.write_text(QUICKSTART.read_text().replace("duration: 12.0", "duration: 60.0")
                        .replace("formats: [csv]", "formats: [csv, mcap]"))
    mount, copy = tmp_path / "small", tmp_path / "copy"
    done = on_tmpfs("size=200k", mount, copy, "run", scenario, "--out", mount / "run", "--quiet")
    assert done.returncode == 2
    assert done.stderr.startswith(f"mobot: error: cannot write {mount / 'run'}/") and done.stderr.endswith(
        f": {NO_SPACE}\n") and "Traceback" not in done.stderr
    run = copy / "run"
    assert_whole_rows(run / "odom" / "mobot.csv")
    assert no_temporaries(run) == [] and not (run / "bag" / "metadata.yaml").exists()
    check = mobot("check", run)
    assert check.returncode == 2
    assert check.stdout.endswith(f"\n  bag can be repaired: mobot check {run} --repair\n")
    repair = mobot("check", run, "--repair")
    assert repair.returncode == 2 and repair.stdout.startswith("repaired bag/bag.mcap: ")
    from rosbags.highlevel import AnyReader

    with AnyReader([run / "bag"]) as reader:
        assert reader.message_count > 0 and reader.message_count == sum(1 for _ in reader.messages())


def test_the_file_size_limit_mid_run_leaves_whole_rows_and_a_summary_saying_error(tmp_path):
    limit = 30_000  # bytes per file: the CSV reaches it mid-way through a flush

    def low_limit():
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    out = tmp_path / "run"
    done = mobot("run", QUICKSTART, "--out", out, "--quiet", preexec_fn=low_limit)
    assert done.returncode == 2
    assert done.stderr == f"mobot: error: cannot write {out / 'odom' / 'mobot.csv'}: {TOO_LARGE}\n"
    rows = assert_whole_rows(out / "odom" / "mobot.csv")
    assert rows > 0 and rows % 50 == 0 and (out / "odom" / "mobot.csv").stat().st_size < limit
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "error"
    assert summary["error"] == f"cannot write {out / 'odom' / 'mobot.csv'}: {TOO_LARGE}"
    assert no_temporaries(out) == []
    check = mobot("check", out)
    assert check.returncode == 2 and "summary.json says 'error': cannot write" in check.stdout


def test_a_path_too_long_for_a_robots_file_mid_run_is_an_error_with_a_summary(tmp_path):
    """PATH_MAX (4096) is passed by odom/<robot>.csv, not by the run folder's own files."""
    robot = "r" * 40
    scenario = tmp_path / "s.yaml"
    scenario.write_text(f"version: 1\nname: deep\nduration: 1.0\nrobots:\n  - {{name: {robot}}}\n")
    out = tmp_path
    while len(str(out)) < 4060 - 201:
        out = out / ("d" * 200)
    out = out / ("d" * (4060 - len(str(out)) - 1))
    assert len(str(out)) == 4060
    done = mobot("run", scenario, "--out", out, "--quiet")
    assert done.returncode == 2
    csv_path = out / "odom" / f"{robot}.csv"
    assert done.stderr == (f"mobot: error: cannot write {csv_path}: File name too long [Errno 36]. Use shorter "
                           "names (scenario, robots, namespaces) or a shorter --out path.\n")
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "error" and summary["error"].startswith(f"cannot write {csv_path}: File name too long")


# the CSV writer itself, where a failing write is injected ---------------------------------


def test_a_write_that_fails_part_way_is_cut_back_to_the_last_whole_row(tmp_path, monkeypatch):
    """os.write that writes part of a flush and then fails, as a full disk does."""
    from mobot_cli.record import sinks

    class State:
        def row(self):
            return (0.5,) * 15

    path = tmp_path / "a.csv"
    csv = sinks.OdomCsv(path)
    state = State()
    for i in range(sinks.FLUSH_EVERY_ROWS):
        csv.write(i, state)
    whole = path.stat().st_size
    real_write, calls = os.write, []

    def failing_write(fd, data):
        calls.append(len(data))
        if len(calls) == 1:
            return real_write(fd, bytes(data[:100]))  # a partial write: half a row lands
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(sinks.os, "write", failing_write)
    with pytest.raises(OSError) as raised:
        for i in range(sinks.FLUSH_EVERY_ROWS):
            csv.write(i, state)
    assert raised.value.errno == errno.ENOSPC and raised.value.filename == str(path)
    assert path.stat().st_size == whole and calls[0] > 100
    monkeypatch.setattr(sinks.os, "write", real_write)
    csv.close()
    assert assert_whole_rows(path) == sinks.FLUSH_EVERY_ROWS
