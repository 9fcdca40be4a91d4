"""`mobot cmd NAME --linear V --angular W [--linear-y V] [--for S]`: drive a robot like a cmd_vel message."""

from __future__ import annotations

from typing import Optional

import typer

from mobot_cli.cli.live import common
from mobot_cli.errors import ExitCode, UsageError


def cmd(
    ctx: typer.Context,
    name: str = typer.Argument(..., help="The robot to drive."),
    linear: float = typer.Option(0.0, "--linear", "-l", help="Forward speed, m/s (negative: backwards)."),
    angular: float = typer.Option(0.0, "--angular", "-a", help="Turn rate, rad/s (positive: left)."),
    linear_y: float = typer.Option(0.0, "--linear-y", "-y",
                                   help="Sideways speed, m/s (positive: left); holonomic robots only."),
    for_: Optional[float] = typer.Option(None, "--for", metavar="S",
                                         help="Stop after S simulated seconds [default: hold until the next cmd]."),
    wait: bool = typer.Option(False, "--wait", help="With --for: return when the command has ended."),
    endpoint: common.Endpoint = None,
    timeout: float = typer.Option(5.0, "--timeout", help=common.TIMEOUT_HELP + " With --wait, "
                                  "the wait for the command to end comes on top."),
    json_: common.Json = False,
) -> int:
    """Command a body twist; it holds until the next cmd, or for S seconds with --for."""
    env = ctx.obj
    if for_ is not None and not for_ > 0:
        raise UsageError(f"--for {for_:g} must be above zero")
    if wait and for_ is None:
        raise UsageError("--wait needs --for: a command without one never ends")
    with common.client(endpoint, timeout) as world:
        budget = timeout + (_wall_bound(world, for_) if wait else 0.0)
        fields = {"name": name, "linear": linear, "angular": angular}
        if linear_y:
            fields["linear_y"] = linear_y
        if for_ is not None:
            fields.update({"for": for_, "wait": wait})
        reply = world.call("cmd", timeout=budget, **fields)
    if json_:
        common.json_out(env, reply)
    common.checked(reply)
    if not json_:
        if wait:
            common.say(env, common.odom_line(reply))
        else:
            ends = f" until step {reply['until_step']}" if reply.get("until_step") is not None else ""
            sideways = f", linear_y {linear_y:g} m/s" if linear_y else ""
            common.say(env, f"'{name}': linear {linear:g} m/s{sideways}, angular {angular:g} rad/s from step "
                            f"{reply['step']}{ends}")
    return ExitCode.OK


def _wall_bound(world, seconds: float) -> float:
    """How long S simulated seconds take on the wall clock at this world's pace (fast: at most that)."""
    rtf = common.checked(world.call("ping")).get("rtf")
    return seconds / rtf if rtf else seconds
