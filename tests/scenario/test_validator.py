"""The Scenario validator kept in the cache folder: the same verdicts as pydantic's own build, and
a cache file is only trusted when this user wrote it and it holds nothing but a validator."""

from __future__ import annotations

import io
import os
import pickle
import subprocess
import sys
from pathlib import Path

import pytest

from mobot_cli.scenario import validator

REPO = Path(__file__).resolve().parents[2]
BAD = sorted((REPO / "tests" / "bad").glob("*.yaml"))
# Prints how the validator was had and what `mobot check`'s validation says of each file.
PROBE = """
import sys
from mobot_cli.errors import MobotError
from mobot_cli.scenario.load import load_scenario
from mobot_cli.scenario.model import Scenario
for path in sys.argv[1:]:
    try:
        print(path, "ok", repr(load_scenario(path)[0]))
    except MobotError as exc:
        print(path, "error", exc.message, exc.location, exc.hint)
print("built" if Scenario.__pydantic_complete__ else "loaded")  # a loaded validator leaves the class unbuilt
"""


def _validate(cache: Path, *paths: Path) -> tuple[str, list[str]]:
    done = subprocess.run([sys.executable, "-c", PROBE, *map(str, paths)], capture_output=True, text=True,
                          env={**os.environ, "MOBOT_CACHE_DIR": str(cache)}, cwd=REPO, check=True)
    *lines, how = done.stdout.splitlines()
    return how, lines


def _cached(cache: Path) -> Path:
    files = list((cache / validator.KIND).glob("scenario-*.pickle"))
    assert len(files) == 1, files
    return files[0]


@pytest.fixture
def scenarios() -> list[Path]:
    return [*sorted((REPO / "scenarios").glob("*.yaml")), *BAD]


def test_the_kept_validator_judges_every_scenario_as_a_new_build_does(tmp_path, scenarios):
    first_how, first = _validate(tmp_path, *scenarios)
    assert first_how == "built" and _cached(tmp_path).stat().st_size > 1000
    again_how, again = _validate(tmp_path, *scenarios)
    assert again_how == "loaded"
    assert again == first and sum(" error " in line for line in again) >= 40  # the rest fail later, resolving


def test_a_file_others_can_write_is_not_trusted(tmp_path):
    scenario = REPO / "scenarios" / "quickstart.yaml"
    _validate(tmp_path, scenario)
    _cached(tmp_path).chmod(0o666)
    assert _validate(tmp_path, scenario)[0] == "built"


@pytest.mark.parametrize("payload", [
    pickle.dumps(os.system),  # a name the unpickler does not find
    b"\x80\x04\x95\x10\x00\x00\x00\x00\x00\x00\x00\x8c\x02os\x94\x8c\x06system\x94\x93\x94.",
    b"not a pickle",
    b"",
])
def test_a_damaged_or_forged_file_is_built_over_and_runs_nothing(tmp_path, payload):
    scenario = REPO / "scenarios" / "quickstart.yaml"
    _validate(tmp_path, scenario)
    _cached(tmp_path).write_bytes(payload)
    _cached(tmp_path).chmod(0o644)
    how, lines = _validate(tmp_path, scenario)
    assert how == "built" and " ok " in lines[0]


def test_a_forged_method_lookup_reaches_nothing_outside_the_models():
    with pytest.raises(pickle.UnpicklingError):
        validator._own_attribute(os, "system")
    with pytest.raises(pickle.UnpicklingError):
        validator._own_attribute(validator.Scenario, "__init_subclass__")  # inherited, not its own
    nothing = validator._Unpickler(io.BytesIO(b""))
    with pytest.raises(pickle.UnpicklingError):
        nothing.find_class("mobot_cli.scenario.limits", "math")  # imported there, not defined
    with pytest.raises(pickle.UnpicklingError):
        nothing.find_class("mobot_cli.scenario.validator", "_save")  # a module of mobot, not of the models
    with pytest.raises(pickle.UnpicklingError):
        nothing.find_class("builtins", "eval")
    assert nothing.find_class("mobot_cli.scenario.model", "Scenario") is validator.Scenario


def test_changed_code_is_another_key(tmp_path, monkeypatch):
    first = validator._key()
    module = tmp_path / "mobot_cli"
    module.mkdir()
    (module / "a.py").write_text("x = 1\n")
    monkeypatch.setattr(validator, "_PACKAGE", module)
    one = validator._key()
    (module / "a.py").write_text("x = 22\n")  # another size (and time)
    assert len({first, one, validator._key()}) == 3
