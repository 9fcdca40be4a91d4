"""Expand xacro files with the ``xacro`` package, resolving ``$(find)`` through mobot's roots.

Results are cached on disk, keyed by the content of every file the expansion read, the
arguments, the environment variables it looked at and the search roots.
"""

# xacro has no public hook for $(find)/$(env)/$(optenv): mobot swaps its private _eval_* table.
# ruff: noqa: SLF001

from __future__ import annotations

import contextlib
import io
import json
import os
import re
import threading
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator, Mapping

from mobot_cli.assets import sandbox
from mobot_cli.assets.lenient import gazebo_xml
from mobot_cli.assets.resources import ResourceResolver
from mobot_cli.common import cache
from mobot_cli.errors import DescriptionError, Location, MobotError, Notice, ResourceError, did_you_mean

# xacro keeps its state in module globals, so expansions must not overlap.
_lock = threading.Lock()

_ARG_DECL = re.compile(r"<xacro:arg\s[^>]*?name\s*=\s*[\"']([^\"']+)[\"']")
_ARG_USE = re.compile(r"\$\(arg\s+([^)\s]+)\s*\)")


@dataclass(frozen=True)
class Expansion:
    """The expanded text of a description plus what it was made from."""

    text: str
    files: tuple[Path, ...]  # the top file first, then every included file
    notices: tuple[Notice, ...] = ()


def is_xacro(path: Path, text: str) -> bool:
    """True for .xacro files and for .urdf files that really are xacro."""
    if Path(path).name.endswith(".xacro"):
        return True
    return "xmlns:xacro" in text or "<xacro:" in text


def expand(path: Path, args: Mapping[str, str], resolver: ResourceResolver) -> str:
    """The expanded URDF text of ``path``; plain URDF comes back unchanged."""
    return expand_file(path, args, resolver).text


def expand_file(path: Path, args: Mapping[str, str] | None,
                resolver: ResourceResolver) -> Expansion:
    """Expand ``path`` (cached), returning its text, the files it read and xacro's warnings."""
    path = Path(path).resolve()
    try:
        top = path.read_bytes()
    except OSError as exc:
        raise ResourceError(f"cannot read robot description {path}: {exc.strerror}",
                            location=Location(file=path),
                            hint="Check the path; relative paths are relative to the scenario's "
                                 "folder.") from None
    text = top.decode("utf-8", errors="replace")
    if not is_xacro(path, text):
        return Expansion(text=text, files=(path,))
    args = {str(k): str(v) for k, v in (args or {}).items()}
    key = cache.digest("xacro", str(path), top, json.dumps(sorted(args.items())),
                       resolver.fingerprint(), *sandbox.cache_marker())
    hit = cache.load("xacro", key)
    if hit is not None and _still_valid(hit):
        return Expansion(text=hit["text"], files=tuple(Path(d[0]) for d in hit["deps"]),
                         notices=tuple(Notice(m, Location(file=path)) for m in hit["notices"]))
    result, env = _run_xacro(path, args, resolver)
    cache.store("xacro", key, {
        "text": result.text,
        "deps": [[str(f), cache.file_digest(f)] for f in result.files],
        "env": sorted(env.items()),
        "notices": [n.message for n in result.notices],
    })
    return result


def _still_valid(entry: dict) -> bool:
    # An entry is only as good as the files and environment variables it was made from.
    try:
        if not all(sandbox.allows(p) for p, _ in entry["deps"]):  # a live spawn may not read them
            return False
        if any(cache.file_digest(Path(p)) != sha for p, sha in entry["deps"]):
            return False
        return all(os.environ.get(name) == value for name, value in entry["env"])
    except (KeyError, TypeError, ValueError):
        return False


def _run_xacro(path: Path, args: dict[str, str],
               resolver: ResourceResolver) -> tuple[Expansion, dict[str, str | None]]:
    import xacro  # lazy: only a cold expansion needs it

    env: dict[str, str | None] = {}
    stderr = io.StringIO()
    with _lock, _patched_substitutions(resolver, env), _lenient_parse(xacro), \
            sandbox.xacro_limits(xacro), contextlib.redirect_stderr(stderr):
        _reset_xacro_state(xacro)
        try:
            doc = xacro.process_file(str(path), mappings=dict(args), verbosity=0)
            text = doc.toprettyxml(indent="  ")
            includes = [Path(f).resolve() for f in xacro.all_includes]
        except Exception as exc:  # noqa: BLE001 - every xacro failure becomes one error
            raise _convert_error(exc, path, xacro) from None
        finally:
            _reset_xacro_state(xacro)
    files = tuple(dict.fromkeys([path, *includes]))
    notices = [Notice(f"xacro: {line.strip()}", Location(file=path))
               for line in stderr.getvalue().splitlines() if line.strip()]
    notices.extend(_unknown_args(args, files, path))
    return Expansion(text=text, files=files, notices=tuple(notices)), env


@contextlib.contextmanager
def _lenient_parse(xacro) -> Iterator[None]:
    """Let xacro read every file as Gazebo's parsers would (assets/lenient.py); the sandbox's own
    parse, entered after this, checks a path before this reads it."""
    original = xacro.parse

    def parse(inp, filename=None):
        if inp is None:
            try:
                with open(os.path.join(xacro.root_dir, filename), encoding="utf-8", errors="replace") as file:
                    inp = file.read()
            except OSError:
                return original(None, filename)  # xacro reports it as it always does
        return original(gazebo_xml(inp) if isinstance(inp, str) else inp, filename)

    xacro.parse = parse
    try:
        yield
    finally:
        xacro.parse = original


def _reset_xacro_state(xacro) -> None:
    xacro.all_includes = []
    xacro.filestack = None
    xacro.macrostack = None
    xacro.root_dir = os.curdir
    xacro.substitution_args_context.clear()


@contextlib.contextmanager
def _patched_substitutions(resolver: ResourceResolver,
                           env: dict[str, str | None]) -> Iterator[None]:
    """Route $(find) through the resolver and record $(env)/$(optenv) reads for the cache."""
    import xacro
    import xacro.substitution_args as sa

    saved = (sa._eval_find, sa._eval_env, sa._eval_optenv, dict(sa._eval_dict))
    original_env, original_optenv = sa._eval_env, sa._eval_optenv

    def find(pkg: str) -> str:
        stack = xacro.filestack or []
        referenced_from = Path(stack[-1]) if stack and stack[-1] else None
        try:
            return str(resolver.find_package(pkg, referenced_from))
        except ResourceError as exc:
            exc.hint = _find_hint(pkg, referenced_from) or exc.hint
            raise

    def read_env(name: str) -> str:
        env[name] = os.environ.get(name)
        return original_env(name)

    def read_optenv(name: str, default: str = "") -> str:
        env[name] = os.environ.get(name)
        return original_optenv(name, default)

    sa._eval_find, sa._eval_env, sa._eval_optenv = find, read_env, read_optenv
    sa._eval_dict.update(find=find, env=read_env, optenv=read_optenv)
    try:
        yield
    finally:
        sa._eval_find, sa._eval_env, sa._eval_optenv = saved[:3]
        sa._eval_dict.clear()
        sa._eval_dict.update(saved[3])


def _find_hint(pkg: str, referenced_from: Path | None) -> str | None:
    """When $(find PKG) only sits in an argument's default, say which argument to pass."""
    if referenced_from is None:
        return None
    try:
        text = referenced_from.read_text(encoding="utf-8", errors="replace")
    except OSError:
        return None
    pattern = re.compile(r"<xacro:arg\s[^>]*?name\s*=\s*[\"']([^\"']+)[\"'][^>]*?"
                         r"default\s*=\s*[\"'][^\"']*\$\(find\s+" + re.escape(pkg) + r"\)")
    match = pattern.search(text)
    if match is None:
        return None
    name = match.group(1)
    return (f"'{pkg}' is only needed by the default of xacro argument '{name}': pass "
            f"{name}:=VALUE in the scenario's args: (any path works if only Gazebo uses it), "
            "or add the folder holding the package to MOBOT_RESOURCE_PATH.")


def _convert_error(exc: Exception, top: Path, xacro) -> MobotError:
    """Turn whatever xacro raised into a DescriptionError naming the file it happened in."""
    from xml.parsers.expat import ExpatError

    stack = [f for f in (xacro.filestack or []) if f]
    current = Path(stack[-1]) if stack else top
    macro = ""
    if xacro.macrostack:
        macro = f" (in macro '{xacro.macrostack[-1].body.getAttribute('name')}')"
    included = f" (included from {top})" if current.resolve() != top else ""
    cause = _innermost(exc)
    if isinstance(cause, MobotError):
        return cause
    if isinstance(cause, ExpatError):
        return DescriptionError(
            f"XML syntax error: {cause}{included}",
            location=Location(file=current, line=getattr(cause, "lineno", None)),
            hint="Check that every tag is closed and every attribute value is quoted.")
    if type(cause).__name__ == "ArgException":
        name = str(cause.args[0]) if cause.args else "?"
        return DescriptionError(
            f"Undefined substitution argument: xacro argument '{name}' is not set and has no "
            f"default{macro}{included}",
            location=Location(file=current, line=_line_of(current, f"$(arg {name})")),
            hint=f"Pass it as {name}:=value in the scenario's args: (or on the command line).")
    if isinstance(cause, OSError) and getattr(cause, "filename", None):
        return DescriptionError(
            f"included file '{cause.filename}' cannot be read: {cause.strerror}{included}",
            location=Location(file=current, line=_line_of(current, Path(cause.filename).name)),
            hint="Check the filename of the <xacro:include>; $(find PKG) resolves through "
                 "MOBOT_RESOURCE_PATH and the other search roots.")
    if isinstance(cause, NameError):
        suffix = getattr(exc, "suffix", None) or ""
        return DescriptionError(
            f"undefined xacro property or name: {cause}{macro}{included}"
            + (f" ({suffix.strip()})" if suffix else ""),
            location=Location(file=current),
            hint="Define it with <xacro:property> before use, or check its spelling.")
    return DescriptionError(f"xacro failed: {exc}{macro}{included}",
                            location=Location(file=current),
                            hint="Run `mobot xacro` on the file to see the problem in context.")


def _innermost(exc: BaseException) -> BaseException:
    """Follow xacro's wrapping (XacroException.exc) down to the original exception."""
    seen = set()
    while id(exc) not in seen:
        seen.add(id(exc))
        inner = getattr(exc, "exc", None)
        if isinstance(inner, BaseException):
            exc = inner
            continue
        break
    return exc


def _line_of(path: Path, needle: str) -> int | None:
    try:
        for number, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
            if needle in line:
                return number
    except OSError:
        pass
    return None


def _unknown_args(args: Mapping[str, str], files: tuple[Path, ...], top: Path) -> list[Notice]:
    """A notice for each passed argument that no file declares or uses (likely a typo)."""
    if not args:
        return []
    known: set[str] = set()
    for path in files:
        try:
            text = path.read_text(encoding="utf-8", errors="replace")
        except OSError:
            continue
        known.update(_ARG_DECL.findall(text))
        known.update(_ARG_USE.findall(text))
    return [Notice(f"xacro argument '{name}' is not used by {top.name}. "
                   + did_you_mean(name, known), Location(file=top, key=f"args.{name}"))
            for name in sorted(args) if name not in known]
