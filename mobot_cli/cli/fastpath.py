"""`mobot run` read without Typer, for the plain forms of its command line.

Starting Typer costs a run ~50 ms (importing Click and Typer, building every command and a
pydantic adapter per option) before any work is done. The usual `mobot run` lines are simple
enough to read here, into exactly the values Typer would pass to run.py; anything else
(--help, a prefixed or joined option such as `--out=DIR` or `-qo DIR`, a value that starts with
`-` or is not a plain number, an option given twice, --ros2 or --view) returns None and goes
through Typer, which reads it, or reports it as it always has. tests/cli/test_fastpath.py holds
the two readers to the same values, output and exit codes.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Callable, Optional

from mobot_cli.cli.environment import Environment

_INT = re.compile(r"(0|[1-9][0-9]{0,17})\Z")  # Typer (pydantic) reads these as int() does
_FLOAT = re.compile(r"(0|[1-9][0-9]{0,14})(\.[0-9]{1,15})?\Z")  # and these as float() does
_VALUED = {"--out": "out", "-o": "out", "--seed": "seed", "--duration": "duration"}
_FLAGS = {"--realtime": "realtime", "--json": "json_", "--quiet": "quiet", "-q": "quiet",
          "--skip-missing": "skip_missing"}


def read(args: list[str]) -> Optional[Callable[[Environment], int]]:
    """The `mobot run` this command line asks for, ready to run on an Environment; None when Typer
    must read the line."""
    if args[:1] == ["--traceback"]:  # the one root option a run line may carry (cli._traceback_asked)
        args = args[1:]
    if args[:1] != ["run"]:
        return None
    options: dict = {"set_": []}
    scenario: Optional[str] = None
    rest = iter(args[1:])
    for arg in rest:
        if arg in _FLAGS:
            if _FLAGS[arg] in options:
                return None
            options[_FLAGS[arg]] = True
        elif arg in _VALUED or arg == "--set":
            value = next(rest, None)
            if value is None or not _plain(value):
                return None
            if arg == "--set":
                options["set_"].append(value)
                continue
            name = _VALUED[arg]
            if name in options:
                return None
            parsed = _value(name, value)
            if parsed is None:
                return None
            options[name] = parsed
        elif arg.startswith("-") or scenario is not None or not _plain(arg):
            return None
        else:
            scenario = arg
    if scenario is None:
        return None

    def command(env: Environment) -> int:
        from mobot_cli.cli.runner import run_scenario

        return run_scenario(env, Path(scenario), **options)

    return command


def _plain(value: str) -> bool:
    """A value Typer passes on as it is: not empty, not an option, no NUL."""
    return bool(value) and not value.startswith("-") and "\0" not in value


def _value(name: str, value: str):
    """An option's value as Typer converts it; None when Typer is left to judge it."""
    if name == "out":
        return Path(value)
    if name == "seed":
        return int(value) if _INT.match(value) else None
    return float(value) if _FLOAT.match(value) else None
