"""Run folders are untrusted input: the attacker's tests for `mobot check DIR`, `mobot plot DIR`
and `mobot view DIR` (issue 26 item 2), and the one reader they share (record/reader.py).

Each hostile folder is a real run folder (a real two-second run with CSV and bag) that is then
damaged: code in a xacro, includes of files outside it, garbage and oversized files, a FIFO, a
symlink out, a folder in a file's place. Every command answers with one located line and exit 2
(or, for check, its status lines and exit 2), never a traceback, never a hang, and writes nothing
outside --out. `mobot view` runs as a process with a timeout: a page left serving fails the test.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mobot_cli.cli import invoke
from mobot_cli.record.plan_loader import PlanRefused
from mobot_cli.record.reader import ReadLimits, RunFolder

REPO = Path(__file__).resolve().parents[2]
SCENARIO = """version: 1
name: attacked
world: empty
duration: 1.0
log: {{rate_hz: 20, formats: [csv, mcap]}}
robots:
  - name: mobot
    description: {description}
"""
EVIL_XACRO = """<?xml version="1.0"?>
<robot xmlns:xacro="http://www.ros.org/wiki/xacro" name="evil">
  {body}
  <link name="base_link"/>
</robot>
"""


@pytest.fixture(scope="module")
def clean_run(tmp_path_factory) -> Path:
    """A real run folder: two seconds of the bundled robot with CSV files and a bag."""
    folder = tmp_path_factory.mktemp("reader")
    scenario = folder / "s.yaml"
    scenario.write_text(SCENARIO.format(description="mobot").replace("duration: 1.0", "duration: 2.0"))
    out = folder / "run"
    assert invoke(["run", scenario, "--out", out, "--quiet"]).exit_code == 0
    return out


@pytest.fixture
def run(clean_run, tmp_path) -> Path:
    """A copy of the clean run to damage; the test's tmp_path holds nothing else but --out."""
    copy = tmp_path / "run"
    shutil.copytree(clean_run, copy)
    return copy


def files_under(root: Path) -> set[str]:
    return {str(p.relative_to(root)) for p in root.rglob("*")}


def view(folder: Path) -> subprocess.CompletedProcess:
    """`mobot view DIR` as a process: exit 2 before serving, or killed (and failed) after 120 s."""
    return subprocess.run([sys.executable, "-m", "mobot_cli", "view", str(folder), "--port", "0"],
                          capture_output=True, text=True, timeout=60, cwd=REPO)


def assert_refused(folder: Path, tmp_path: Path, *, expect: str = "", view_too: bool = True,
                   check_too: bool = True) -> None:
    """plot, check and view each exit 2 with one line, no traceback, nothing written outside --out.

    ``check_too=False``: `mobot check DIR` says how the run ended from its files and never expands
    scenario.yaml, so a hostile robot leaves its verdict alone (it must still not run anything)."""
    before = files_under(tmp_path)
    out = tmp_path / "out" / "plot.png"
    plot = invoke(["plot", folder, "--out", out])
    check = invoke(["check", folder])
    assert "Traceback" not in check.stderr + check.stdout
    outcomes = {"plot": (plot.exit_code, plot.stderr)}
    if check_too:
        outcomes["check"] = (check.exit_code, check.stderr + check.stdout)
    if view_too:
        shown = view(folder)
        outcomes["view"] = (shown.returncode, shown.stderr)
    for command, (code, text) in outcomes.items():
        assert code == 2, (command, text)
        assert "Traceback" not in text, (command, text)
    for command in ("plot", "view") if view_too else ("plot",):
        line = outcomes[command][1]
        assert line.count("\n") == 1 and line.startswith("mobot: error: "), (command, line)
        assert expect in line, (command, line)
    assert files_under(tmp_path) == before, "a command wrote outside --out"


def evil_robot(run: Path, body: str) -> None:
    (run / "robot.urdf.xacro").write_text(EVIL_XACRO.format(body=body))
    (run / "scenario.yaml").write_text(SCENARIO.format(description="robot.urdf.xacro"))


# Each writes the marker with stock xacro (tests/live/test_security.py shows they do).
EXPLOITS = {
    "$(eval) with open": """<xacro:property name="cmd" value="eval open('{marker}', 'w').write('owned')"/>
<link name="$(${{cmd}})"/>""",
    "comprehension reaches os.system": """<link name="${{[c.__init__.__globals__['system']('echo owned > {marker}') \
for c in [0] for c in c.__class__.__base__.__subclasses__() if c.__name__ == '_wrap_close']}}"/>""",
    "lambda": """<link name="${{(lambda: [c for c in ().__class__.__base__.__subclasses__()])()}}{marker}"/>""",
}


@pytest.mark.parametrize("name", sorted(EXPLOITS))
def test_code_in_a_shipped_xacro_does_not_run(run, tmp_path, name):
    marker = tmp_path / "pwned"
    evil_robot(run, EXPLOITS[name].format(marker=marker))
    assert_refused(run, tmp_path, expect="scenario.yaml: ", check_too=False)
    assert not marker.exists()


def test_includes_of_files_outside_the_folder_are_refused(run, tmp_path):
    secret = tmp_path / "home" / ".ssh" / "id_rsa"
    secret.parent.mkdir(parents=True)
    secret.write_text("<robot><link name='SECRET'/></robot>")
    for body in (f'<xacro:include filename="{secret}"/>', '<xacro:include filename="/etc/passwd"/>',
                 '<xacro:include filename="$(find mobot_description)/../../../../../../etc/passwd"/>',
                 '<link name="m"><collision><geometry><mesh filename="file:///etc/passwd"/></geometry></collision>'
                 '<inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/>'
                 '</inertial></link>'
                 '<joint name="j" type="fixed"><parent link="base_link"/><child link="m"/></joint>'):
        evil_robot(run, body)
        assert_refused(run, tmp_path, expect="scenario.yaml: refused: ", view_too="ssh" in body, check_too=False)


def test_a_world_outside_the_folder_is_not_read(run, tmp_path):
    (run / "scenario.yaml").write_text(SCENARIO.format(description="mobot").replace("world: empty",
                                                                                   "world: /etc/passwd"))
    assert_refused(run, tmp_path, expect="scenario.yaml: refused: ", view_too=False, check_too=False)


@pytest.mark.parametrize("damage", ["truncated", "garbage", "huge", "folder", "fifo", "symlink"])
def test_a_damaged_summary(run, tmp_path, damage):
    summary = run / "summary.json"
    text = summary.read_bytes()
    summary.unlink()
    if damage == "truncated":
        summary.write_bytes(text[: len(text) // 2])
    elif damage == "garbage":
        summary.write_bytes(b"\xff\xfe{[" * 100)
    elif damage == "huge":
        with summary.open("wb") as f:
            f.truncate(ReadLimits().summary + 1)  # sparse: the size is what is checked
    elif damage == "folder":
        summary.mkdir()
    elif damage == "fifo":
        os.mkfifo(summary)
    else:
        summary.symlink_to("/etc/passwd")
    assert_refused(run, tmp_path, expect="summary.json", view_too=damage in ("fifo", "huge", "folder"))


@pytest.mark.parametrize("damage", ["nan", "garbage", "long line", "fifo", "symlink", "folder"])
def test_a_damaged_odometry_csv(run, tmp_path, damage):
    csv = run / "odom" / "mobot.csv"
    header = csv.read_text().splitlines()[0]
    csv.unlink()
    if damage == "nan":
        csv.write_text(header + "\n" + ",".join(["nan"] * 16) + "\n" + ",".join(["inf"] * 16) + "\n")
    elif damage == "garbage":
        csv.write_bytes(b"\x00\x01garbage\n" * 50)
    elif damage == "long line":
        csv.write_text(header + "\n" + "1" * 200_000 + "\n")
    elif damage == "fifo":
        os.mkfifo(csv)
    elif damage == "symlink":
        csv.symlink_to("/etc/passwd")
    else:
        csv.mkdir()
    expect = {"nan": "no odometry", "garbage": "no odometry"}.get(damage, "odom/mobot.csv")
    outcome = invoke(["plot", run, "--out", tmp_path / "out.png"])
    assert (outcome.exit_code, outcome.stderr.count("\n")) == (2, 1) and expect in outcome.stderr, outcome.stderr
    assert_refused(run, tmp_path, expect="", view_too=damage in ("fifo", "nan", "long line"))


@pytest.mark.parametrize("damage", ["truncated", "fifo", "symlink"])
def test_a_damaged_bag(run, tmp_path, damage):
    mcap = run / "bag" / "bag.mcap"
    data = mcap.read_bytes()
    mcap.unlink()
    if damage == "truncated":
        mcap.write_bytes(data[: len(data) // 3])
    elif damage == "fifo":
        os.mkfifo(mcap)
    else:
        mcap.symlink_to("/etc/passwd")
    check = invoke(["check", run])
    assert check.exit_code == 2 and "Traceback" not in check.stderr + check.stdout
    shown = view(run)
    assert shown.returncode == 2 and shown.stderr.count("\n") == 1 and "bag" in shown.stderr, shown.stderr


def test_a_folder_that_points_out_is_refused(run, tmp_path):
    outside = tmp_path / "elsewhere"
    shutil.move(run / "odom", outside)
    (run / "odom").symlink_to(outside)
    assert_refused(run, tmp_path, expect="odom points outside the run folder", view_too=False)


def test_the_reader_reads_a_clean_run(clean_run):
    folder = RunFolder.open(clean_run)
    assert folder.summary().scenario == "attacked"
    header, rows = folder.numeric_rows("odom/mobot.csv")
    assert header[0] == "t" and len(rows) == pytest.approx(41, abs=2)  # 2 s at 20 Hz, both ends
    notices: list[str] = []
    plan = folder.plan(notices, "missing")
    assert notices == [] and [r.name for r in plan.robots] == ["mobot"]
    assert folder.bag_folder() == clean_run / "bag"


def test_a_scenario_that_loads_forever_is_stopped_by_its_cpu_limit(run):
    """A billion laughs in xacro macros: stopped by RLIMIT_CPU (or its memory) in the loader process."""
    body = "".join(f'<xacro:macro name="m{i}"><xacro:m{i - 1}/><xacro:m{i - 1}/></xacro:macro>'
                   for i in range(1, 40))
    evil_robot(run, '<xacro:macro name="m0"><link name="l"/></xacro:macro>' + body + "<xacro:m39/>")
    limits = ReadLimits(plan_seconds=2.0, plan_memory=512 << 20)
    with pytest.raises(PlanRefused) as caught:
        RunFolder.open(run, limits).plan([], "missing")
    assert "scenario.yaml" in str(caught.value) and "\n" not in str(caught.value)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(name=st.sampled_from(["summary.json", "odom/mobot.csv", "bag/metadata.yaml"]),
       cut=st.floats(0, 1), noise=st.binary(max_size=64), at=st.floats(0, 1))
def test_damaged_files_never_give_a_traceback(clean_run, tmp_path_factory, name, cut, noise, at):
    run = tmp_path_factory.mktemp("fuzz") / "run"
    shutil.copytree(clean_run, run)
    data = (run / name).read_bytes()
    data = data[: int(len(data) * cut)]
    i = int(len(data) * at)
    (run / name).write_bytes(data[:i] + noise + data[i:])
    for args in (["check", run], ["plot", run, "--out", run.parent / "out.png"]):
        outcome = invoke(args)
        assert outcome.exit_code in (0, 1, 2), outcome
        assert "Traceback" not in outcome.stderr + outcome.stdout
        if outcome.exit_code == 2 and args[0] == "plot":
            assert outcome.stderr.count("\n") == 1


def test_a_sweep_does_not_follow_a_run_linked_from_outside(clean_run, tmp_path):
    sweep = tmp_path / "sweep"
    (sweep / "runs").mkdir(parents=True)
    (sweep / "sweep.json").write_text('{"runs": [{"folder": "runs/0000", "params": {"robots.mobot.pose.yaw": 1}}]}')
    shutil.copytree(clean_run, sweep / "runs" / "0000")
    (sweep / "runs" / "0001").symlink_to(clean_run)  # a run outside the sweep folder
    outcome = invoke(["plot", sweep, "--out", tmp_path / "sweep.png"])
    assert (outcome.exit_code, outcome.stdout) == (0, f"wrote {tmp_path / 'sweep.png'} (1 path)\n"), outcome


def test_history_lines_that_are_not_events_are_left_out(run):
    (run / "history.jsonl").write_text('{"op": "spawn", "name": "a"}\n[1, 2]\nnot json\n{"op": "delete"\n'
                                       '{"op": "delete", "name": "a"}\n')
    assert [e["op"] for e in RunFolder.open(run).history()] == ["spawn", "delete"]


@pytest.mark.parametrize("damage", ["fifo", "huge", "symlink"])
def test_a_damaged_scenario_yaml(run, tmp_path, damage):
    scenario = run / "scenario.yaml"
    scenario.unlink()
    if damage == "fifo":
        os.mkfifo(scenario)
    elif damage == "huge":
        scenario.write_text("#" * (ReadLimits().scenario + 1))
    else:
        scenario.symlink_to("/etc/passwd")
    assert_refused(run, tmp_path, expect="scenario.yaml", view_too=damage == "fifo", check_too=False)
    check = invoke(["check", run])  # the run's verdict: scenario.yaml is not a file it can count on
    assert check.exit_code == 2 and "Traceback" not in check.stderr + check.stdout


def test_limits_are_settings(run, tmp_path, monkeypatch):
    """MOBOT_RUN_FOLDER_LIMITS lowers (or raises) a limit; a bad entry is one line, exit 2."""
    out = tmp_path / "out.png"
    assert invoke(["plot", run, "--out", out]).exit_code == 0
    monkeypatch.setenv("MOBOT_RUN_FOLDER_LIMITS", "csv=0.001")
    small = invoke(["plot", run, "--out", out])
    assert small.exit_code == 2 and "odom/mobot.csv is larger than 1048 bytes" in small.stderr
    monkeypatch.setenv("MOBOT_RUN_FOLDER_LIMITS", "csv=nan")
    bad = invoke(["plot", run, "--out", out])
    assert (bad.exit_code, bad.stderr.count("\n")) == (2, 1)
    assert bad.stderr.startswith("mobot: error: MOBOT_RUN_FOLDER_LIMITS: 'csv=nan' is not NAME=NUMBER")
