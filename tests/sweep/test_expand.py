"""Runs that differ only in their seed share one preparation: the same plans, resolved YAML and
errors as preparing each run on its own."""

from __future__ import annotations

from dataclasses import astuple
from pathlib import Path

import pytest

from mobot_cli.cli import invoke
from mobot_cli.scenario.prepare import prepare
from mobot_cli.sweep.expand import expand
from mobot_cli.sweep.spec import build_spec

REPO = Path(__file__).resolve().parents[2]
NOISY = """version: 1
name: noisy
duration: 1
seed: 9
robots:
  - name: r
    args: {lidar: "true"}
    sensors: {lidar: {rate_hz: 10, samples: 90, noise_stddev: 0.02}}
    drive: {odometry: encoder}
"""


def one_by_one(path: Path, overrides: list[str]):
    return prepare(path, overrides)


@pytest.mark.parametrize("name", ["quickstart", "fleet", "events", "coverage", "house"])
def test_seed_sweeps_of_bundled_scenarios_match_preparing_each_run(name):
    path = REPO / "scenarios" / f"{name}.yaml"
    sweep = expand(build_spec(path, ["seed=0,7,4294967295"], [], [], None, None, []))
    assert [v.seed for v in sweep.variants] == [0, 7, 4294967295]
    for variant, run in zip(sweep.variants, sweep.prepared):
        alone = one_by_one(path, [f"seed={variant.seed}"])
        assert run.resolved_yaml == alone.resolved_yaml
        assert run.plan == alone.plan and run.scenario == alone.scenario


def test_derived_seeds_with_sensors_noise_and_another_axis(tmp_path):
    path = tmp_path / "noisy.yaml"
    path.write_text(NOISY)
    sweep = expand(build_spec(path, ["robots.r.pose.x=0,1"], [], [], None, 5, ["duration=2"]))
    assert len(sweep.prepared) == 2
    for variant, run in zip(sweep.variants, sweep.prepared):
        alone = one_by_one(path, ["duration=2", *variant.overrides(), f"seed={variant.seed}"])
        assert (run.resolved_yaml, run.plan, run.scenario) == (alone.resolved_yaml, alone.plan, alone.scenario)
    assert f"seed: {sweep.variants[1].seed}\n" in sweep.prepared[1].resolved_yaml
    # The grid and the seed together: four runs, each its own seed and x.
    sweep = expand(build_spec(path, ["robots.r.pose.x=0,1", "seed=3,4"], [], [], None, None, []))
    plans = [p.plan for p in sweep.prepared]
    assert [(p.robots[0].pose.xyz[0], p.seed) for p in plans] == [(0, 3), (0, 4), (1, 3), (1, 4)]
    for variant, run in zip(sweep.variants, sweep.prepared):
        alone = one_by_one(path, variant.overrides())
        assert (run.resolved_yaml, run.plan) == (alone.resolved_yaml, alone.plan)


@pytest.mark.parametrize("values, message", [
    ("1,-1", "mobot: error: --grid seed=1,-1, key 'seed': Input should be greater than or equal to 0"),
    ("1,4294967296", "key 'seed': Input should be less than 4294967296"),
    ("1,abc", "mobot: error: --grid seed=1,abc, key 'seed': "),
])
def test_a_bad_seed_in_a_seed_sweep_is_still_refused_where_it_was_given(values, message, tmp_path):
    path = tmp_path / "noisy.yaml"
    path.write_text(NOISY)
    code, out, err = astuple(invoke(["sweep", path, "--grid", f"seed={values}", "--out", tmp_path / "out"]))
    assert (code, out) == (2, "") and message in err, err
    assert not (tmp_path / "out").exists()


def test_seeds_written_otherwise_are_prepared_in_full(tmp_path):
    path = tmp_path / "noisy.yaml"
    path.write_text(NOISY)
    sweep = expand(build_spec(path, ["seed=2,0x10,010, 3 "], [], [], None, None, []))
    for variant, run in zip(sweep.variants, sweep.prepared):
        alone = one_by_one(path, variant.overrides())
        assert (run.resolved_yaml, run.plan) == (alone.resolved_yaml, alone.plan)
    assert [v.seed for v in sweep.variants] == [2, 16, 8, 3]
