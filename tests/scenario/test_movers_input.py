"""A scenario's ``movers:``: any input is a run or one located error (exit 2), never a traceback."""

from __future__ import annotations

import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mobot_cli.cli import invoke

numbers = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-10, 10), st.booleans(),
                    st.text(max_size=3))
point = st.lists(numbers, min_size=0, max_size=3)
item = st.fixed_dictionaries({}, optional={
    "name": st.one_of(st.sampled_from(["bob", "w_{i}", "a b", "", "x" * 70]), st.text(max_size=5)),
    "shape": st.one_of(st.sampled_from(["person", "box", "cylinder", "cone"]), numbers),
    "size": st.lists(numbers, max_size=4),
    "path": st.one_of(st.lists(point, max_size=4), numbers),
    "mode": st.sampled_from(["loop", "pingpong", "once", "bounce"]),
    "region": st.lists(numbers, max_size=5),
    "start": point,
    "speed": numbers,
    "at": numbers,
    "count": numbers,
    "extra": numbers,
})


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.lists(item, min_size=1, max_size=3))
def test_any_movers_item_is_checked_or_refused_with_a_location(tmp_path, movers):
    path = tmp_path / "m.yaml"
    path.write_text(yaml.safe_dump({"version": 1, "duration": 1, "movers": movers}))
    done = invoke(["check", str(path)])
    assert done.exit_code in (0, 2), done
    assert "Traceback" not in done.stderr
    if done.exit_code == 2:
        assert done.stderr.startswith("mobot: error: ") and "m.yaml" in done.stderr
        assert done.stderr.count("\n") == 1


def test_a_valid_fleet_checks():
    from mobot_cli.scenario.mover_model import MoverSpec

    spec = MoverSpec(name="w_{i}", count=3, region=(0, 1, 0, 1))
    assert spec.shape == "person" and spec.speed == 1.0
