"""The Scenario validator, kept in mobot's cache folder between processes.

Pydantic builds a model's validator in Python from its classes: ~30 ms for the Scenario, in
every process that validates one (each `mobot run`'s helper, `mobot check`, a live world, the
API). pydantic-core makes the same validator from its pickle, the built schema, in ~1 ms. So
the first process builds it as pydantic does and keeps it as ``validators/scenario-KEY.pickle``
in the cache folder; the next ones load it from there. KEY covers what the schema is built
from: mobot's version and every one of its source files (path, size, modification time),
pydantic's and pydantic-core's versions and Python's.

A cache file is read as one another program could have written. Only a regular file owned by
this user and writable by no one else is opened, and its unpickler finds nothing but what a
Scenario validator holds: the scenario models and their validator functions, pydantic's
comparison functions, functools.partial and pydantic-core's SchemaValidator. Any other name,
a damaged or stale file, no cache folder: the validator is built as pydantic builds it, and a
run is never failed by its cache.
"""

from __future__ import annotations

import functools
import hashlib
import io
import os
import pickle
import sys
from pathlib import Path

from mobot_cli.scenario.model import Scenario

KIND = "validators"
KEEP = 4  # cache files kept: the newest, for checkouts used in turn
_PACKAGE = Path(__file__).resolve().parent.parent  # mobot_cli/
# The modules whose classes and validator functions a Scenario validator holds.
_MODELS = {f"mobot_cli.scenario.{name}" for name in ("model", "sensor_model", "goal_model", "expect_model", "limits")}
_HOOK = "__get_pydantic_json_schema__"  # BaseModel's classmethod, in every model's schema metadata
_ALLOWED = {  # other names a Scenario validator's pickle refers to
    ("functools", "partial"),
    ("pydantic_core._pydantic_core", "SchemaValidator"),
    ("pydantic._internal._validators", "greater_than_validator"),
    ("pydantic._internal._validators", "greater_than_or_equal_validator"),
    ("pydantic._internal._validators", "less_than_validator"),
    ("pydantic._internal._validators", "less_than_or_equal_validator"),
}


@functools.cache
def scenario_validator():
    """The validator of a Scenario (``validate_python`` makes one), from the cache when it can."""
    path = _cache_file()
    loaded = _load(path) if path is not None else None
    if loaded is not None:
        return loaded
    Scenario.model_rebuild()  # defer_build: built here, once per process
    validator = Scenario.__pydantic_validator__
    if path is not None:
        _save(path, validator)
    return validator


def _cache_file() -> Path | None:
    from mobot_cli.common.cache import cache_dir

    try:
        return cache_dir() / KIND / f"scenario-{_key()}.pickle"
    except (OSError, RuntimeError):  # a source file gone, no home folder: no caching
        return None


def _key() -> str:
    import pydantic
    import pydantic_core

    from mobot_cli import __version__

    sha = hashlib.sha256(f"{__version__} {pydantic.VERSION} {pydantic_core.__version__} {sys.version}".encode())
    for folder, dirs, files in os.walk(_PACKAGE):
        dirs[:] = sorted(d for d in dirs if d != "__pycache__")
        for name in sorted(f for f in files if f.endswith(".py")):
            info = os.stat(os.path.join(folder, name))
            sha.update(f"{folder}/{name} {info.st_size} {info.st_mtime_ns}\n".encode())
    return sha.hexdigest()[:32]


def _load(path: Path):
    from mobot_cli.common.cachedir import read_own

    try:
        data = read_own(path)
        if data is None:
            return None
        validator = _Unpickler(io.BytesIO(data)).load()
    except Exception:  # unreadable, damaged, refused or made by other code: build it instead
        return None
    from pydantic_core import SchemaValidator

    return validator if isinstance(validator, SchemaValidator) else None


def _save(path: Path, validator) -> None:
    """Pickle ``validator`` atomically into the cache; keep the newest few (a cache never fails)."""
    from mobot_cli.common.files import write_bytes_atomic

    try:
        data = pickle.dumps(validator, protocol=pickle.HIGHEST_PROTOCOL)
        path.parent.mkdir(parents=True, exist_ok=True)
        write_bytes_atomic(path, data, durable=False)
        kept = sorted(path.parent.glob("scenario-*.pickle"), key=lambda p: p.stat().st_mtime_ns, reverse=True)
        for old in kept[KEEP:]:
            old.unlink(missing_ok=True)
    except Exception:  # unpicklable (a plugin's validator), a read-only folder, a race with another run
        pass


class _Unpickler(pickle.Unpickler):
    """Finds only what a Scenario validator holds (see the module's text)."""

    def find_class(self, module: str, name: str):
        if module == "builtins" and name == "getattr":
            return _own_attribute
        if (module, name) in _ALLOWED:
            return super().find_class(module, name)
        if module in _MODELS and module in sys.modules:  # loaded already: nothing runs on import
            found = super().find_class(module, name)
            if getattr(found, "__module__", None) == module:  # defined there, not imported into it
                return found
        raise pickle.UnpicklingError(f"{module}.{name} is not part of a Scenario validator")


def _own_attribute(owner: object, name: str):
    """getattr as a pickle uses it for methods: only a scenario model's own (its validators) or the
    one pydantic hook its schema refers to (the JSON schema's, bound to the model)."""
    if isinstance(owner, type) and owner.__module__ in _MODELS and (name in vars(owner) or name == _HOOK):
        return getattr(owner, name)
    raise pickle.UnpicklingError(f"{name} is not an attribute of a scenario model")
