"""Limits for robot descriptions a live client sends: what they may read and what xacro may run.

Inside ``confined(roots, files)`` (live spawns; a user's own scenario files never enter it):

- every file read on a description's behalf (the top file, ``<xacro:include>``,
  ``xacro.load_yaml``, globbed includes, meshes and other resource URIs) must resolve, symlinks
  followed, inside one of ``roots`` or be one of ``files``; otherwise ``OutsideRoots``;
- xacro expressions (``${...}`` and ``$(eval ...)``) are checked before they run: no name or
  attribute starting with ``_``, no frame, code or generator attributes, no ``str.format``, no
  generator expressions; ``python.vars`` and ``python.type`` are gone and ``$(eval)`` sees only
  a few plain builtins. Stock xacro only checks the outer code object's names (a comprehension
  or lambda hides ``__class__`` from it) and evaluates ``$(eval)`` with every builtin;
- environment variables are not read: ``$(optenv NAME DEFAULT)`` gives DEFAULT and
  ``$(env NAME)`` is an error (the server's environment is not the client's).

Time and memory are limited by the process that loads (mobot_cli/live/worker.py), not here.
"""

# xacro has no public hook for its evaluation and substitutions: mobot confines its private
# _eval_* table, _global_symbols and _DictWrapper.
# ruff: noqa: SLF001

from __future__ import annotations

import ast
import builtins
import contextlib
import glob as globmodule
import os
import types
from contextvars import ContextVar
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterator

from mobot_cli.errors import DescriptionError

# Attributes that lead from an ordinary value to Python's machinery: frames (and through
# them every module's globals), code objects, and str.format's own attribute lookups.
_BANNED_ATTRIBUTES = frozenset({"format", "format_map", "mro"})
_BANNED_PREFIXES = ("_", "gi_", "cr_", "ag_", "f_", "co_", "tb_", "func_")
_BANNED_NODES = (ast.GeneratorExp, ast.Yield, ast.YieldFrom, ast.Await)  # generators carry frames
_HIDDEN_PYTHON = ("vars", "type")  # vars(cls)['__subclasses__'] and type(type(x)) reach everything
_PLAIN_BUILTINS = ("abs", "all", "any", "bool", "dict", "divmod", "enumerate", "filter", "float",
                   "frozenset", "int", "isinstance", "len", "list", "map", "max", "min", "ord",
                   "range", "repr", "reversed", "round", "set", "slice", "sorted", "str", "sum",
                   "tuple", "zip")
HINT = ("A live spawn may read only the named description's own package (or folder), the "
        "request's base_dir and the resource search path (MOBOT_RESOURCE_PATH, ROS_PACKAGE_PATH, ...).")


class OutsideRoots(DescriptionError):
    """A confined description tried to read a file outside the folders it may read."""


class Forbidden(DescriptionError):
    """A confined xacro expression uses something that could escape the expression language."""


class LimitExceeded(DescriptionError):
    """A confined xacro expression ran out of the loader's memory."""


@dataclass(frozen=True)
class Confinement:
    """The folders (and single files) a confined description may read."""

    roots: tuple[Path, ...]
    files: tuple[Path, ...] = ()

    def allows(self, path: str | os.PathLike) -> bool:
        """True when ``path``, symlinks resolved, is one of the files or inside a root."""
        try:
            resolved = Path(path).resolve()
        except (OSError, RuntimeError, ValueError):
            return False
        return resolved in self.files or any(resolved.is_relative_to(root) for root in self.roots)


_ACTIVE: ContextVar[Confinement | None] = ContextVar("mobot_confinement", default=None)


@contextlib.contextmanager
def confined(roots, files=()) -> Iterator[Confinement]:
    """Confine the descriptions loaded inside the block to ``roots`` and ``files``."""
    confinement = Confinement(roots=tuple(_resolved(r) for r in roots),
                              files=tuple(_resolved(f) for f in files))
    token = _ACTIVE.set(confinement)
    try:
        yield confinement
    finally:
        _ACTIVE.reset(token)


def active() -> bool:
    """True inside ``confined``."""
    return _ACTIVE.get() is not None


def allows(path: str | os.PathLike) -> bool:
    """True outside ``confined``, else whether the confinement allows reading ``path``."""
    confinement = _ACTIVE.get()
    return confinement is None or confinement.allows(path)


def check(path: str | os.PathLike, what: str) -> None:
    """OutsideRoots when a confined description may not read ``path``; ``what`` names it as written."""
    if not allows(path):
        raise OutsideRoots(f"{what} is outside the folders a live spawn may read", hint=HINT)


def cache_marker() -> tuple[str, ...]:
    """An extra cache-key part that keeps confined expansions apart from a user's own."""
    return ("confined",) if active() else ()


def check_expression(expr: str) -> None:
    """Forbidden when a xacro expression could reach past plain values; syntax errors pass through."""
    try:
        tree = ast.parse(expr.strip(), mode="eval")
    except (SyntaxError, ValueError, RecursionError, MemoryError):
        return  # xacro's own compile reports it
    for node in ast.walk(tree):
        bad = None
        if isinstance(node, _BANNED_NODES):
            bad = "a generator expression"
        elif isinstance(node, ast.Attribute):
            if node.attr.startswith(_BANNED_PREFIXES) or node.attr in _BANNED_ATTRIBUTES:
                bad = f"the attribute '{node.attr}'"
        elif isinstance(node, (ast.Name, ast.arg, ast.keyword)):
            name = node.id if isinstance(node, ast.Name) else node.arg
            if name and name.startswith("_"):
                bad = f"the name '{name}'"
        if bad is not None:
            raise Forbidden(f"xacro expression '{_short(expr)}' uses {bad}, which a live spawn may not use",
                            hint="Live spawns evaluate plain arithmetic, strings, lists and the "
                                 "python./math./xacro. helpers, without Python's internals.")


@contextlib.contextmanager
def xacro_limits(xacro: types.ModuleType) -> Iterator[None]:
    """Within a confinement, patch the xacro module's evaluation and file access (restored after)."""
    if not active():
        yield
        return
    import xacro.substitution_args as sa

    saved_xacro = {name: getattr(xacro, name) for name in
                   ("safe_eval", "_global_symbols", "load_yaml", "parse", "glob")}
    saved_sa = {name: getattr(sa, name) for name in ("_eval", "_eval_env", "_eval_optenv")}
    saved_dict = dict(sa._eval_dict)
    original_eval, original_load_yaml, original_parse = (
        saved_xacro["safe_eval"], saved_xacro["load_yaml"], saved_xacro["parse"])

    def safe_eval(expr, globals, locals=None):
        check_expression(expr)
        try:
            return original_eval(expr, globals, locals)
        except MemoryError:
            raise LimitExceeded(f"xacro expression '{_short(expr)}' needs more memory than a live spawn "
                                "may use", hint="Live spawns load within `mobot serve --load-memory`.") from None

    def load_yaml(filename):
        check(xacro.abs_filename_spec(filename), f"xacro.load_yaml file '{filename}'")
        return original_load_yaml(filename)

    def parse(inp, filename=None):
        if inp is None:
            check(os.path.join(xacro.root_dir, filename), f"included file '{filename}'")
        return original_parse(inp, filename)

    def env(name):
        raise DescriptionError(f"$(env {name}) is not available to a live spawn: the server's "
                               "environment is not the client's",
                               hint=f"Pass the value as a xacro argument ({name.lower()}:=VALUE).")

    def optenv(name, default=""):
        return default

    def dollar_eval(expr, context):
        check_expression(expr)
        args = context.setdefault("arg", {})
        functions = {"arg": lambda name: sa.convert_value(sa._eval_arg(name, args=args), "auto"),
                     "dirname": lambda: sa._eval_dirname(context["filename"]),
                     **{k: v for k, v in sa._eval_dict.items() if not k.startswith("_")}}
        return str(eval(expr, {"__builtins__": _plain_builtins()},  # noqa: S307 - checked above, plain builtins only
                        sa._DictWrapper(args, functions)))

    xacro.safe_eval, xacro.load_yaml, xacro.parse = safe_eval, load_yaml, parse
    xacro.glob = types.SimpleNamespace(glob=_confined_glob)
    xacro._global_symbols = _restricted_symbols(xacro, saved_xacro["_global_symbols"], load_yaml)
    sa._eval, sa._eval_env, sa._eval_optenv = dollar_eval, env, optenv
    sa._eval_dict.update(env=env, optenv=optenv)
    try:
        yield
    finally:
        for name, value in saved_xacro.items():
            setattr(xacro, name, value)
        for name, value in saved_sa.items():
            setattr(sa, name, value)
        sa._eval_dict.clear()
        sa._eval_dict.update(saved_dict)


def _restricted_symbols(xacro: types.ModuleType, symbols: dict[str, Any], load_yaml) -> dict[str, Any]:
    """xacro's global symbols without python.vars/python.type, load_yaml confined."""
    out = dict(symbols)
    python = xacro.NameSpace()
    dict.update(python, {k: v for k, v in symbols["python"].items() if k not in _HIDDEN_PYTHON})
    helpers = xacro.NameSpace()
    dict.update(helpers, {**symbols["xacro"], "load_yaml": load_yaml})
    out.update(python=python, xacro=helpers, load_yaml=load_yaml)
    return out


def _confined_glob(pattern: str) -> list[str]:
    """glob.glob, refused when the pattern's fixed folder is outside; matches outside are dropped."""
    fixed = pattern
    for index, char in enumerate(pattern):
        if char in "*?[":
            fixed = os.path.dirname(pattern[:index]) or "."
            break
    check(fixed, f"included files matching '{pattern}'")
    return [match for match in globmodule.glob(pattern) if allows(match)]


def _plain_builtins() -> dict[str, Any]:
    return {name: getattr(builtins, name) for name in _PLAIN_BUILTINS}


def _short(expr: str) -> str:
    expr = expr.strip()
    return expr if len(expr) <= 80 else expr[:77] + "..."


def _resolved(path: str | os.PathLike) -> Path:
    return Path(path).expanduser().resolve()
