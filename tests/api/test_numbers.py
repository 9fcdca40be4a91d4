"""Numbers at the edge (issue 26): NaN, infinities and absurd values through the scenario, the
Python API and the Gymnasium env are refused with mobot's own located error, before the world is
touched, and a Simulation closed afterwards still writes its summary."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mobot_cli.api import Simulation
from mobot_cli.errors import MobotError, UsageError
from mobot_cli.scenario.limits import MAX_ANGULAR_SPEED, MAX_SPEED, MIN_SPACING
from mobot_cli.scenario.prepare import prepare

REPO = Path(__file__).resolve().parents[2]
QUICKSTART = REPO / "scenarios" / "quickstart.yaml"
BAD = [math.nan, math.inf, -math.inf, 1e308, -1e308, 1e6]
floats = st.floats(allow_nan=True, allow_infinity=True) | st.sampled_from(BAD)


@pytest.fixture(scope="module")
def sim(tmp_path_factory):
    """One simulation for the whole module (a world costs seconds); its summary is checked last."""
    out = tmp_path_factory.mktemp("numbers") / "run"
    simulation = Simulation.open(QUICKSTART, out=out, overrides=["robots.mobot.commands=[]"])
    yield simulation
    simulation.close()


def _odom(sim) -> tuple[float, ...]:
    s = sim.state("mobot")
    return (s.odom_x, s.odom_y, s.odom_yaw, s.odom_vx, s.odom_wz)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(linear=floats, angular=floats, duration=st.none() | floats)
def test_api_twists_are_finite_and_bounded_or_refused_first(sim, linear, angular, duration):
    step, before = sim.step_count, _odom(sim)
    ok = (math.isfinite(linear) and abs(linear) <= MAX_SPEED and math.isfinite(angular)
          and abs(angular) <= MAX_ANGULAR_SPEED
          and (duration is None or (math.isfinite(duration) and 0 < duration <= 1e6)))
    if ok:
        sim.command("mobot", linear, angular, duration=duration)
        sim.command("mobot", 0.0, 0.0)
        return
    with pytest.raises(UsageError) as caught:
        sim.command("mobot", linear, angular, duration=duration)
    assert isinstance(caught.value, MobotError) and "\n" not in str(caught.value)
    assert any(unit in caught.value.message for unit in ("m/s", "rad/s", " s "))
    assert sim.step_count == step and _odom(sim) == before  # refused before the world saw it


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(x=floats, y=floats, setting=st.sampled_from(["max_linear", "max_angular", "acceleration", "timeout"]),
       value=floats)
def test_api_goals_and_durations_refuse_non_finite_numbers(sim, x, y, setting, value):
    step = sim.step_count
    limit = {"max_linear": MAX_SPEED, "max_angular": MAX_ANGULAR_SPEED, "acceleration": 1000.0, "timeout": 1e6}
    if not (math.isfinite(x) and math.isfinite(y) and abs(x) <= 1e6 and abs(y) <= 1e6
            and math.isfinite(value) and 0 < value <= limit[setting]):
        with pytest.raises(MobotError):
            sim.goto("mobot", x, y, **{setting: value})
    for seconds in (math.nan, math.inf, -1.0, 1e308):
        with pytest.raises(UsageError, match=r"run_for: seconds: .* s "):
            sim.run_for(seconds)
    assert sim.step_count == step


def test_a_simulation_refused_nan_still_writes_its_summary(tmp_path):
    with Simulation.open(QUICKSTART, out=tmp_path / "run", overrides=["robots.mobot.commands=[]"]) as sim:
        with pytest.raises(UsageError, match=r"command 'mobot': linear: nan m/s is not a finite number"):
            sim.command("mobot", math.nan, 0.0)
        sim.command("mobot", 0.5, 0.0)
        sim.run_for(1.0)
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["status"] == "ok"
    odom = (tmp_path / "run" / "odom" / "mobot.csv").read_text().splitlines()
    assert "nan" not in "".join(odom).lower()


@settings(max_examples=60, deadline=None)
@given(field=st.sampled_from(["linear", "angular", "wheel_radius", "spacing", "max_linear", "for"]),
       value=st.floats(allow_nan=False, allow_infinity=False) | st.sampled_from([1e308, -1e308, 1e-320, 5e-324]))
def test_scenario_numbers_are_bounded_with_unit_and_limit(tmp_path_factory, field, value):
    folder = tmp_path_factory.mktemp("scn")
    command = {"linear": f"{{at: 1, linear: {value!r}}}", "angular": f"{{at: 1, angular: {value!r}}}",
               "spacing": f"{{at: 1, coverage: {{area: [0, 2, 0, 2], spacing: {value!r}}}}}",
               "max_linear": f"{{at: 1, goto: {{x: 1, y: 0}}, max_linear: {value!r}}}",
               "for": f"{{at: 1, linear: 0.1, for: {value!r}}}"}.get(field)
    robot = (f"    drive: {{wheel_radius: {value!r}}}\n" if field == "wheel_radius"
             else f"    commands:\n      - {command}\n")
    path = folder / "s.yaml"
    path.write_text(f"version: 1\nduration: 2\nrobots:\n  - name: mobot\n{robot}")
    try:
        prepare(path)
    except MobotError as exc:
        text = str(exc)
        assert "\n" not in text and "s.yaml:" in text
        if (field == "linear" and abs(value) > MAX_SPEED) or (field == "max_linear" and value > MAX_SPEED):
            assert f"is beyond the limit of {MAX_SPEED:g} m/s" in text
        if field == "spacing" and 0 < value < MIN_SPACING:
            assert f"is below the limit of {MIN_SPACING:g} m" in text
        return
    # accepted: within the documented bounds
    limit = {"linear": MAX_SPEED, "angular": MAX_ANGULAR_SPEED, "wheel_radius": 10.0, "spacing": 1e6,
             "max_linear": MAX_SPEED, "for": 1e6}[field]
    assert abs(value) <= limit
    if field == "spacing":
        assert value >= MIN_SPACING and 2 / value <= 10_000


@settings(max_examples=200, deadline=None)
@given(op=st.sampled_from(["cmd", "goto"]), field=st.sampled_from(["linear", "angular", "x", "y", "max_linear"]),
       value=floats)
def test_live_requests_take_the_same_bounds(op, field, value):
    from mobot_cli.live.protocol import Refusal
    from mobot_cli.live.schema import parse

    document = {"op": op, "name": "r", **({"x": 0.0, "y": 0.0} if op == "goto" else {})}
    if op == "cmd" and field not in ("linear", "angular"):
        field = "linear"
    if op == "goto" and field in ("linear", "angular"):
        field = "max_linear"
    document[field] = value
    limit = {"linear": MAX_SPEED, "angular": MAX_ANGULAR_SPEED, "max_linear": MAX_SPEED, "x": 1e6, "y": 1e6}[field]
    ok = math.isfinite(value) and abs(value) <= limit and (field != "max_linear" or value > 0)
    if ok:
        assert getattr(parse(document), field) == value
        return
    with pytest.raises(Refusal) as caught:
        parse(document)
    assert f"field '{field}'" in str(caught.value) and "\n" not in str(caught.value)
