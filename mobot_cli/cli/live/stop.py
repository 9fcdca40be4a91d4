"""`mobot stop`: shut the live world down cleanly (it writes its record first)."""

from __future__ import annotations

import typer

from mobot_cli.cli.live import common
from mobot_cli.errors import ExitCode


def stop(
    ctx: typer.Context,
    endpoint: common.Endpoint = None,
    timeout: common.Timeout = 5.0,
) -> int:
    """Stop the live world at the endpoint."""
    with common.client(endpoint, timeout) as world:
        reply = common.checked(world.call("stop"))
    common.say(ctx.obj, f"stopped the live world at {world.endpoint} at t={reply['t']:.3f} s")
    return ExitCode.OK
