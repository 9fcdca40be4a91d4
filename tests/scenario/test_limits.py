"""Untrusted input is refused by name, quickly, with exit 2 and no run folder.

Files that cannot be golden files in git (a FIFO, /dev/zero, a directory, a file over the
size limit) and the edges of each documented limit: the last value accepted, the first
refused. tests/bad/ holds the golden texts of the other cases.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from mobot_cli.cli import invoke
from mobot_cli.errors import ScenarioError, UsageError
from mobot_cli.scenario.load import load_scenario
from mobot_cli.scenario.prepare import prepare
from mobot_cli.scenario.yamlsafe import MAX_DEPTH, MAX_NODES, MAX_YAML_BYTES
from mobot_cli.scenario.yamlsource import parse_value, parse_yaml
from tests.scenario.mutations import cpu_seconds

REPO = Path(__file__).resolve().parents[2]
QUICKSTART = REPO / "scenarios" / "quickstart.yaml"
SMALL = "version: 1\nduration: 2\n"


def run_cli(args: list[str]) -> tuple[int, str]:
    outcome = invoke(args)
    return outcome.exit_code, outcome.stderr


def refused_by_run(path: Path, tmp_path) -> str:
    out = tmp_path / "run"
    code, err = run_cli(["run", str(path), "--out", str(out), "--quiet"])
    assert code == 2 and not out.exists()
    assert err.count("\n") == 1 and "Traceback" not in err
    return err


def test_fifo_is_refused_without_opening_it(tmp_path):
    fifo = tmp_path / "pipe.yaml"
    os.mkfifo(fifo)
    # Opened, the FIFO would block the run for ever: the timeout catches that (and only that).
    result = subprocess.run([sys.executable, "-m", "mobot_cli", "run", str(fifo), "--out", str(tmp_path / "r")],
                            capture_output=True, text=True, timeout=600)
    assert result.returncode == 2
    assert result.stderr == (f"mobot: error: {fifo}: the scenario is a FIFO (named pipe), not a regular file. "
                             "Give the path of a scenario YAML file.\n")
    assert not (tmp_path / "r").exists()


def test_device_is_refused(tmp_path):
    err = refused_by_run(Path("/dev/zero"), tmp_path)
    assert err == ("mobot: error: /dev/zero: the scenario is a character device, not a regular file. "
                   "Give the path of a scenario YAML file.\n")


def test_directory_is_refused(tmp_path):
    folder = tmp_path / "scenario.yaml"
    folder.mkdir()
    err = refused_by_run(folder, tmp_path)
    assert err == (f"mobot: error: {folder}: the scenario is a directory, not a regular file. "
                   "Give the path of a scenario YAML file.\n")


def test_file_over_the_size_limit_is_refused_and_one_at_it_loads(tmp_path):
    big = tmp_path / "big.yaml"
    padding = "#" * 99 + "\n"
    body = SMALL + padding * ((MAX_YAML_BYTES - len(SMALL)) // len(padding))
    big.write_text(body + "#" * (MAX_YAML_BYTES - len(body)))
    assert big.stat().st_size == MAX_YAML_BYTES
    assert load_scenario(big)[0].duration == 2.0
    with big.open("a") as handle:
        handle.write("#")
    err = refused_by_run(big, tmp_path)
    assert err == (f"mobot: error: {big}: the scenario file is larger than 1 MiB. "
                   "That is far beyond any scenario: is it the right file?\n")


def test_file_that_reports_size_zero_is_still_read_with_a_bound():
    # /proc files say st_size 0; the reader reads at most the limit and parses what is there.
    with pytest.raises(ScenarioError) as info:
        load_scenario("/proc/self/status")
    assert info.value.message.startswith("malformed YAML")


def test_sweep_file_fifo_is_refused(tmp_path):
    fifo = tmp_path / "sweep.yaml"
    os.mkfifo(fifo)
    code, err = run_cli(["sweep", str(fifo), "--grid", "seed=1,2", "--out", str(tmp_path / "s")])
    assert code == 2 and not (tmp_path / "s").exists()
    assert "the scenario is a FIFO (named pipe), not a regular file" in err


def test_alias_bomb_is_refused_quickly(tmp_path):
    lines = [SMALL, "a0: &a0 [l, l, l, l, l, l, l, l, l]"]
    lines += [f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 9) + "]" for i in range(1, 9)]
    started = cpu_seconds()  # CPU time: what expanding the aliases would burn; waiting is not it
    with pytest.raises(ScenarioError, match=f"more than {MAX_NODES} values once its aliases"):
        load_scenario(_write(tmp_path, "\n".join(lines)))
    assert cpu_seconds() - started < 10


def test_node_budget_edge():
    # The root list + 99 lists of 1000 values (98 of them aliases) + `rest` values: each alias counts again.
    def text(rest: int) -> str:
        return "[&a [" + "0," * 999 + "]," + "*a," * 98 + "1," * rest + "]"

    assert 1 + 99 * 1000 + 999 == MAX_NODES
    assert len(parse_yaml(text(999), None).data) == 99 + 999
    with pytest.raises(ScenarioError, match="more than 100000 values"):
        parse_yaml(text(1000), None)


def test_depth_edge():
    deepest = MAX_DEPTH - 1  # the root mapping is one level
    parse_yaml("a: " + "[" * deepest + "]" * deepest, None)
    with pytest.raises(ScenarioError, match=f"nests deeper than {MAX_DEPTH} levels") as info:
        parse_yaml("a: 1\nb: " + "[" * (deepest + 1) + "]" * (deepest + 1), Path("x.yaml"))
    assert info.value.location.line == 2


def test_alias_to_its_own_anchor_is_refused():
    with pytest.raises(ScenarioError, match="nests deeper than"):
        parse_yaml("a: &a [*a]", None)


@pytest.mark.parametrize("text, message", [
    ("seed: !!python/object/apply:os.system [echo]", "the YAML tag '!!python/object/apply:os.system' is not allowed"),
    ("seed: !!binary aGVsbG8=", "the YAML tag '!!binary' is not allowed"),
    ("seed: !!timestamp 2024-01-02", "the YAML tag '!!timestamp' is not allowed"),
    ("robots: !!set {a, b}", "the YAML tag '!!set' is not allowed"),
    ("seed: !custom 1", "the YAML tag '!custom' is not allowed"),
    ("seed: !!int ''", "'' cannot be read as !!int"),
    ("skip_missing: !!bool maybe", "'maybe' cannot be read as !!bool"),
    ("seed: " + "9" * 5000, "cannot be read as !!int"),
    ("\x00seed: 1", "malformed YAML: unacceptable character #x0000"),
    ("a: [&x 1, &x 2]", "malformed YAML: found duplicate anchor 'x'"),
])
def test_refused_yaml_is_located(tmp_path, text, message):
    with pytest.raises(ScenarioError) as info:
        load_scenario(_write(tmp_path, SMALL + text))
    assert message in info.value.message
    assert info.value.location.line == 3
    assert "\n" not in str(info.value)


def test_invalid_utf8_names_its_line(tmp_path):
    path = tmp_path / "s.yaml"
    path.write_bytes(SMALL.encode() + b"name: caf\xe9\n")
    with pytest.raises(ScenarioError, match=rf"not UTF-8 text \(byte {len(SMALL) + 9}\)") as info:
        load_scenario(path)
    assert info.value.location.line == 3


def test_dates_stay_text_and_exponents_are_numbers(tmp_path):
    scenario, _ = load_scenario(_write(tmp_path, "version: 1\nname: 2024-01-02\nduration: 1e1\nsettle: 5E-1\n"))
    assert scenario.name == "2024-01-02"
    assert scenario.duration == 10.0 and scenario.settle == 0.5


@pytest.mark.parametrize("override", [
    "physics.rate_hz=true", "seed=false", "duration=true", "settle=true", "log.rate_hz=true",
    "physics.gravity=[0, 0, true]", "robots.mobot.pose.x=true", "robots.mobot.commands.0.at=true",
    "robots.mobot.commands.0.linear=true", "robots.mobot.commands.0.for=true", "version=true",
])
def test_booleans_are_not_numbers(override):
    with pytest.raises(ScenarioError, match="expected a number, got true|expected a number, got false|"
                                            "unsupported version true"):
        prepare(QUICKSTART, [override])


def test_boolean_collisions_in_expect_are_refused():
    with pytest.raises(ScenarioError, match="expected a number, got true"):
        prepare(REPO / "scenarios" / "expectations.yaml", ["expect.1.collisions=true"])


@pytest.mark.parametrize("override, message", [
    ("robots.mobot.args={x0: &a [l,l,l,l,l,l,l,l,l,l], x1: &b [*a,*a,*a,*a,*a,*a,*a,*a,*a,*a], "
     "x2: &c [*b,*b,*b,*b,*b,*b,*b,*b,*b,*b], x3: &d [*c,*c,*c,*c,*c,*c,*c,*c,*c,*c], "
     "x4: [*d,*d,*d,*d,*d,*d,*d,*d,*d,*d]}", "more than 100000 values once its aliases"),
    ("seed=!!python/name:os.system", "the YAML tag '!!python/name:os.system' is not allowed"),
    ("robots.mobot.args=" + "[" * 40 + "]" * 40, "nests deeper than 32 levels"),
    ("seed=2024-13-45", "got '2024-13-45'"),
    ("duration=1e308", "1e+308 s is longer than the limit of 1e+06 s"),
])
def test_set_values_have_the_same_protections(override, message, tmp_path):
    code, err = run_cli(["run", str(QUICKSTART), "--set", override, "--out", str(tmp_path / "r")])
    assert code == 2 and not (tmp_path / "r").exists()
    assert message in err and err.count("\n") == 1
    assert err.startswith("mobot: error: --set ") and len(err) < 400


def test_set_value_that_is_not_yaml_stays_text():
    assert parse_value("[abc") == "[abc"


@pytest.mark.parametrize("override, accepted", [
    ("duration=1000000", True), ("duration=1000000.5", False),
    ("robots.mobot.commands.2.for=1e6", True), ("robots.mobot.commands.2.for=1.1e6", False),
    ("log.rate_hz=0.001", True), ("log.rate_hz=0.0009", False),
    ("physics.rate_hz=10000", True), ("physics.rate_hz=10001", False),
    ("physics.gravity=[0, 600, -800]", True), ("physics.gravity=[0, 600, -800.1]", False),
    ("physics.gravity=[1e308, 1e308, 0]", False),
    ("robots.mobot.pose.y=-1e6", True), ("robots.mobot.pose.y=-1.000001e6", False),
    ("name=" + "s" * 64, True), ("name=" + "s" * 65, False),
])
def test_limit_edges(override, accepted):
    if accepted:
        prepare(QUICKSTART, [override])
    else:
        with pytest.raises(ScenarioError):
            prepare(QUICKSTART, [override])


def test_robot_name_edge_keeps_todays_charset(tmp_path):
    ok = "r_" + "x" * 61 + "9"
    fleet = "  - name: _a{i}\n    count: 2\n    poses: [[0, 1, 0], [0, 2, 0]]\n"
    scenario, _ = load_scenario(_write(tmp_path, SMALL + f"robots:\n  - name: {ok}\n" + fleet))
    assert [r.name for r in scenario.robots] == [ok, "_a{i}"]
    with pytest.raises(ScenarioError, match="it is 65 characters long, the limit is 64"):
        load_scenario(_write(tmp_path, SMALL + f"robots:\n  - {{name: {ok}x}}\n"))


def test_world_and_description_refuse_control_characters():
    with pytest.raises(ScenarioError, match="holds a control character"):
        prepare(QUICKSTART, ['robots.mobot.description="mobot\\n"'])


def test_sweep_file_uses_the_safe_reader(tmp_path):
    from mobot_cli.sweep.spec import load_sweep_file

    path = _write(tmp_path, f"scenario: {QUICKSTART}\ngrid:\n  seed: !!python/name:os.system\n")
    with pytest.raises(ScenarioError, match="the YAML tag '!!python/name:os.system' is not allowed") as info:
        load_sweep_file(path)
    assert (info.value.location.line, info.value.location.key) == (3, "grid.seed")


def test_sweep_name_is_bounded(tmp_path):
    from mobot_cli.sweep.spec import load_sweep_file

    path = _write(tmp_path, f"scenario: {QUICKSTART}\nname: {'n' * 65}\ngrid: {{seed: [1, 2]}}\n")
    with pytest.raises(ScenarioError, match="not a valid sweep name: it is 65 characters long"):
        load_sweep_file(path)


def test_grid_value_with_a_tag_names_the_flag(tmp_path):
    code, err = run_cli(["sweep", str(QUICKSTART), "--grid", "seed=1,!!python/name:os.system",
                         "--out", str(tmp_path / "s")])
    assert code == 2 and not (tmp_path / "s").exists()
    assert err.startswith("mobot: error: --grid seed=1,!!python/name:os.system")
    assert "the YAML tag '!!python/name:os.system' is not allowed" in err


def test_sweep_of_too_many_runs_is_refused_up_front(tmp_path):
    started = cpu_seconds()  # CPU time: preparing 10^8 runs would burn hours of it
    code, err = run_cli(["sweep", str(QUICKSTART), "--random", "seed=0:100", "--samples", "100000000",
                         "--out", str(tmp_path / "s")])
    assert code == 2 and cpu_seconds() - started < 10
    assert err == ("mobot: error: --samples: the sweep has 100,000,000 runs, more than the limit of 10,000. "
                   "Every run is prepared before the first starts; split the sweep.\n")


def test_random_bounds_must_be_finite():
    from mobot_cli.sweep.spec import flag_axes

    with pytest.raises(UsageError, match="random bounds must be finite numbers, got inf"):
        flag_axes([], [], ["seed=0:.inf"])


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "s.yaml"
    path.write_text(text)
    return path
