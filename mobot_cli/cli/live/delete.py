"""`mobot delete NAME`: remove a robot from the live world."""

from __future__ import annotations

from typing import Optional

import typer

from mobot_cli.cli.live import common
from mobot_cli.errors import ExitCode


def delete(
    ctx: typer.Context,
    name: str = typer.Argument(..., help="The robot to remove."),
    endpoint: Optional[str] = common.ENDPOINT,
    timeout: float = typer.Option(5.0, "--timeout", help=common.TIMEOUT_HELP),
    json_: bool = typer.Option(False, "--json", help="Print the reply as JSON."),
) -> int:
    """Remove a robot from the live world."""
    with common.client(endpoint, timeout) as world:
        reply = world.call("delete", name=name)
    if json_:
        common.json_out(ctx.obj, reply)
    common.checked(reply)
    if not json_:
        common.say(ctx.obj, f"deleted '{name}' at t={reply['t']:.3f} s")
    return ExitCode.OK
