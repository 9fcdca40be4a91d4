"""`mobot odom NAME [--follow]`: a robot's odometry, ground truth and command."""

from __future__ import annotations

import time
from typing import Optional

import typer

from mobot_cli.cli import live_common
from mobot_cli.errors import ExitCode


def odom(
    ctx: typer.Context,
    name: str = typer.Argument(..., help="The robot to read."),
    follow: bool = typer.Option(False, "--follow", "-f", help="Keep printing readings until Ctrl-C."),
    rate: float = typer.Option(10.0, "--rate", help="Readings per second (wall clock) with --follow."),
    endpoint: Optional[str] = live_common.ENDPOINT,
    timeout: float = typer.Option(5.0, "--timeout", help=live_common.TIMEOUT_HELP),
    json_: bool = typer.Option(False, "--json", help="Print replies as JSON (one line each with --follow)."),
) -> int:
    """Print a robot's odometry (odom frame = its spawn pose), ground truth and command."""
    env = ctx.obj
    with live_common.client(endpoint, timeout) as world:
        reply = world.call("odom", name=name)
        if not follow or not reply.get("ok"):
            if json_:
                live_common.json_out(env, reply)
            live_common.checked(reply)
            if not json_:
                live_common.say(env, live_common.odom_line(reply))
            return ExitCode.OK
        return _follow(env, world, name, reply, max(0.1, min(rate, 1000.0)), json_)


def _follow(env, world, name: str, reply: dict, rate: float, json_: bool) -> int:
    import json

    last = None
    try:
        while True:
            if not reply.get("ok"):
                live_common.status(env, f"'{name}' is gone: {reply.get('result')}: {reply.get('message')}")
                return ExitCode.OK
            if reply["step"] != last:
                last = reply["step"]
                live_common.say(env, json.dumps(reply) if json_ else live_common.odom_line(reply))
            time.sleep(1.0 / rate)
            reply = world.call("odom", name=name)
    except KeyboardInterrupt:
        return ExitCode.OK
