"""Property: any mutation of a bundled scenario or sweep file loads or is refused with a MobotError.

A small seeded sample runs in the default suite; `python3 bench/fuzz_scenarios.py` runs
thousands and prints the counts.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.scenario.mutations import BUNDLED, check, mutated, override, workspace

SAMPLE = settings(max_examples=60, derandomize=True, deadline=None, database=None,
                  suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


@pytest.fixture(scope="module")
def root(tmp_path_factory) -> Path:
    return workspace(tmp_path_factory.mktemp("fuzz"))


def _relative(original: Path) -> Path:
    return original.relative_to(original.parents[1] if original.parent.name == "sweeps" else original.parent)


@pytest.mark.parametrize("original", BUNDLED, ids=[str(_relative(p)) for p in BUNDLED])
@SAMPLE
@given(data=st.data())
def test_mutated_file_loads_or_is_refused(original: Path, data, root: Path):
    text = data.draw(mutated(original))
    path = root / _relative(original).with_name("mutated-" + original.name)
    path.write_bytes(text)
    check(path)


@pytest.mark.parametrize("original", BUNDLED, ids=[str(_relative(p)) for p in BUNDLED])
@settings(SAMPLE, max_examples=20)
@given(data=st.data())
def test_mutated_set_value_loads_or_is_refused(original: Path, data, root: Path):
    item = data.draw(override(original))
    check(root / _relative(original), [item])
