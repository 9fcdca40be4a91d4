"""`mobot stop`: shut the live world down cleanly (it writes its record first)."""

from __future__ import annotations

from typing import Optional

import typer

from mobot_cli.cli.live import common
from mobot_cli.errors import ExitCode


def stop(
    ctx: typer.Context,
    endpoint: Optional[str] = common.ENDPOINT,
    timeout: float = typer.Option(5.0, "--timeout", help=common.TIMEOUT_HELP),
) -> int:
    """Stop the live world at the endpoint."""
    with common.client(endpoint, timeout) as world:
        reply = common.checked(world.call("stop"))
    common.say(ctx.obj, f"stopped the live world at {world.endpoint} at t={reply['t']:.3f} s")
    return ExitCode.OK
