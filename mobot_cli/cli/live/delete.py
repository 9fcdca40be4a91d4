"""`mobot delete NAME`: remove a robot from the live world."""

from __future__ import annotations

import typer

from mobot_cli.cli.live import common
from mobot_cli.errors import ExitCode


def delete(
    ctx: typer.Context,
    name: str = typer.Argument(..., help="The robot to remove."),
    endpoint: common.Endpoint = None,
    timeout: common.Timeout = 5.0,
    json_: common.Json = False,
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
