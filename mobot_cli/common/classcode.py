"""Code Python compiles from text as modules load, compiled once a machine, not once a process:
the `mobot` command's start.

Making a dataclass writes its methods (``__init__``, ``__eq__``, ``__repr__``, ...) as Python
text and compiles it, each time the class is made: ~1 ms a class, most of it in the compiler.
A `mobot run` makes about 40 before its loop and its helper about 80 (mobot's plan and record
types, and pydantic's and annotated-types' own), which came to a fifth of their imports. And
every annotation a typed dict or a model keeps as text becomes a ``typing.ForwardRef``, which
compiles it: pydantic-core's schema types alone are ~700 of them, ~8 ms of the helper's start.

Both processes start with ``install()`` (the entry point calls it, before anything else is
imported): from then on the code of those texts comes from ``classcode/PYTHON.marshal`` in the
cache folder, where the process that first compiled a text left it (``save()``, at exit). The
text is the key and the code is what ``compile`` makes of it, so a class is the same either way;
a text not yet there (new code, another Python) is compiled as before and kept.

This relies on one detail of CPython's ``dataclasses`` and ``typing`` (3.10 to 3.13): they run
or compile such text with the built-in ``exec`` and ``compile``, looked up in their module's
globals, where ``install()`` puts functions that do the same with the kept code. Were that to
change, the functions would simply never be called. Only the `mobot` command installs them: the
Python API leaves its caller's process as it is.

The cache file is read as .pyc files are, as code this user's processes wrote: only a regular
file owned by this user and writable by no one else is read, and a damaged one is ignored (and
replaced). Anything that goes wrong here costs the time it was to save, never a run.
"""

import builtins
import dataclasses
import marshal
import sys
import typing

KIND = "classcode"
MAX_ENTRIES = 2048  # ~twice what all commands together make; above it a save keeps the texts its process used
_TAG = f"{sys.implementation.cache_tag}-{sys.hexversion:x}"  # a code object is one Python's
_codes: dict = {}  # "exec\n" or "eval\n", then the text -> its code
_used: set = set()  # texts this process ran
_fresh = False  # a text was compiled here: save() has something to keep
_installed = False


def install() -> None:
    """Load the cache, and have dataclasses and forward references made from now on use it; once a
    process."""
    global _installed
    if _installed:
        return
    _installed = True
    _codes.update(_load())
    dataclasses.exec = _exec  # each shadows the built-in for that module alone
    typing.compile = _compile
    import atexit

    atexit.register(save)


def save() -> None:
    """Keep the texts this process compiled, with those already kept (a cache never fails)."""
    global _fresh
    if not _fresh:
        return
    _fresh = False
    try:
        from mobot_cli.common.files import write_bytes_atomic

        path = _path()
        codes = {**_load(), **_codes}  # another process may have kept others meanwhile
        if len(codes) > MAX_ENTRIES:
            codes = {text: code for text, code in codes.items() if text in _used}
        path.parent.mkdir(parents=True, exist_ok=True)
        write_bytes_atomic(path, marshal.dumps(codes), durable=False)
    except Exception:  # a read-only folder, no home folder, a full disk
        pass


def _exec(source, /, *args, **kwargs):
    """``exec`` for dataclasses: a text runs its kept code."""
    return builtins.exec(_code(source, "exec") if type(source) is str else source, *args, **kwargs)


def _compile(source, filename, mode, *args, **kwargs):
    """``compile`` for typing's forward references (``compile(text, '<string>', 'eval')``)."""
    if type(source) is str and filename == "<string>" and mode == "eval" and not (args or kwargs):
        return _code(source, mode)
    return builtins.compile(source, filename, mode, *args, **kwargs)


def _code(source: str, mode: str):
    """The code of ``source``, compiled as dataclasses and typing compile it (no __future__ flags:
    neither module has any), from the cache or compiled now and kept."""
    global _fresh
    key = f"{mode}\n{source}"
    code = _codes.get(key)
    if code is None:
        code = _codes[key] = builtins.compile(source, "<string>", mode, dont_inherit=True)
        _fresh = True
    _used.add(key)
    return code


def _path():
    from mobot_cli.common.cachedir import cache_dir

    return cache_dir() / KIND / f"{_TAG}.marshal"


def _load() -> dict:
    """The kept texts and their code; empty when there is no file or it is not to be trusted."""
    from mobot_cli.common.cachedir import read_own

    try:
        data = read_own(_path())
    except (OSError, RuntimeError):  # unreadable, no home folder
        return {}
    try:
        codes = marshal.loads(data) if data is not None else {}
    except Exception:  # damaged: compiled again, and the file replaced
        return {}
    code_type = type(_load.__code__)
    if type(codes) is not dict or not all(type(t) is str and type(c) is code_type for t, c in codes.items()):
        return {}
    return codes
