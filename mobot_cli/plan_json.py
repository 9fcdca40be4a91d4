"""Plans (and answers holding them) as JSON and back, for a process that hands its parent a plan.

A confined process that resolved an untrusted description (record/plan_loader.py: a run folder's
scenario; live/worker.py: a spawned robot) answers its parent in JSON, never a pickle: unpickling
runs whatever the bytes say, so a subverted child would run code in the parent. The parent
validates the answer against its type with pydantic (which already validates scenario files):
strict types (no string for a number, no float for an int), no key a dataclass does not have and
none missing, so only the plan's own dataclasses and plain values come out, and nothing runs but
their validation. The child writes with the standard library's json (no schema to build first):
every field of every dataclass, tuples as arrays. Floats round-trip bit for bit; inf and nan are
JSON's ``Infinity`` and ``NaN`` tokens.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import numbers
import os
from typing import Any


@functools.lru_cache(maxsize=None)
def adapter(kind: Any):
    """The pydantic TypeAdapter that checks a ``kind`` (built once per type: ~0.1 s for a Plan)."""
    from pydantic import ConfigDict, TypeAdapter

    # The config reaches the plan's dataclasses, which have none of their own (pydantic refuses a
    # config beside a bare dataclass: the answer types are tuples holding them).
    return TypeAdapter(kind, config=ConfigDict(strict=True, extra="forbid"))


def dump(value: Any) -> bytes:
    """``value`` (dataclasses, tuples, lists, text, numbers, booleans, None) as UTF-8 JSON; ValueError
    for anything else, or for text UTF-8 cannot hold (a file name's undecodable bytes)."""
    try:
        return json.dumps(_plain(value), allow_nan=True, ensure_ascii=False, separators=(",", ":")).encode("utf-8")
    except UnicodeEncodeError as exc:
        raise ValueError(f"text that is not UTF-8: {exc.object[exc.start:exc.end]!a}") from None


def _plain(value: Any) -> Any:
    if value is None or type(value) in (str, int, float, bool):
        return value
    if isinstance(value, str):
        return str(value)
    if isinstance(value, os.PathLike) and isinstance(os.fspath(value), str):  # a path where the plan says text
        return os.fspath(value)
    if isinstance(value, numbers.Integral):  # numpy's integers too: their value, as an int
        return int(value)
    if isinstance(value, numbers.Real):
        return float(value)
    if isinstance(value, (tuple, list)):
        return [_plain(item) for item in value]
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: _plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    raise ValueError(f"a {type(value).__name__} has no JSON form here")


def load(kind: Any, data: bytes, limit: int) -> Any:
    """The value of type ``kind`` that ``data`` holds; ValueError (one line, no input echoed) when
    ``data`` is longer than ``limit`` bytes, is not JSON, or does not validate as a ``kind``."""
    from pydantic import ValidationError

    if len(data) > limit:
        raise ValueError(f"{len(data)} bytes, more than the {limit} allowed")
    try:
        return adapter(kind).validate_json(data)
    except ValidationError as exc:
        first = exc.errors(include_url=False, include_context=False, include_input=False)[0]
        where = ".".join(str(part) for part in first["loc"])
        more = exc.error_count() - 1
        text = first["msg"] + (f" at {where}" if where else "") + (f" (and {more} more)" if more > 0 else "")
        raise ValueError(" ".join(text.split())[:300]) from None
