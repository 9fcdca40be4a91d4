"""`mobot goto NAME X Y [--yaw YAW] [--wait]`: drive a live robot to a point, as a goal command does."""

from __future__ import annotations

from typing import Optional

import typer

from mobot_cli.cli.live import common
from mobot_cli.errors import ExitCode, UsageError

# With --wait and no --goal-timeout, wait at most this long (wall seconds) for the goal to end.
WAIT_WITHOUT_TIMEOUT = 3600.0


def goto(
    ctx: typer.Context,
    name: str = typer.Argument(..., help="The robot to drive."),
    x: float = typer.Argument(..., help="Goal x in the world frame, m."),
    y: float = typer.Argument(..., help="Goal y in the world frame, m."),
    yaw: Optional[float] = typer.Option(None, "--yaw", help="Turn to this heading once there, rad."),
    tolerance: Optional[float] = typer.Option(None, "--tolerance",
                                              help="How close counts as there, m [default: 0.05]."),
    goal_timeout: Optional[float] = typer.Option(None, "--goal-timeout", metavar="S",
                                                 help="Give up after S simulated seconds [default: no limit]."),
    ground_truth: bool = typer.Option(False, "--ground-truth",
                                      help="Steer by the true pose instead of the robot's odometry."),
    max_linear: Optional[float] = typer.Option(None, "--max-linear", help="Top speed, m/s [default: 0.3]."),
    max_angular: Optional[float] = typer.Option(None, "--max-angular", help="Top turn rate, rad/s [default: 1.0]."),
    wait: bool = typer.Option(False, "--wait", help="Return when the goal has ended: reached, timed out or blocked."),
    planner: Optional[str] = typer.Option(None, "--planner", metavar="astar",
                                          help="Plan around the world's obstacles (A* on its map)."),
    inflation: Optional[float] = typer.Option(None, "--inflation", metavar="M",
                                              help="With --planner: keep this far from obstacles, m "
                                                   "[default: the robot's footprint radius]."),
    endpoint: common.Endpoint = None,
    timeout: float = typer.Option(5.0, "--timeout", help=common.TIMEOUT_HELP + " With --wait, "
                                  "the wait for the goal comes on top."),
    json_: common.Json = False,
) -> int:
    """Drive a robot of the live world to (X, Y) with the goal controller; exit 1 when --wait
    sees it end other than reached."""
    env = ctx.obj
    for flag, value in (("--tolerance", tolerance), ("--goal-timeout", goal_timeout),
                        ("--max-linear", max_linear), ("--max-angular", max_angular)):
        if value is not None and not value > 0:
            raise UsageError(f"{flag} {value:g} must be above zero")
    fields = {"name": name, "x": x, "y": y, "yaw": yaw, "tolerance": tolerance, "timeout": goal_timeout,
              "localization": "ground_truth" if ground_truth else None, "max_linear": max_linear,
              "max_angular": max_angular, "wait": wait, "planner": planner, "inflation": inflation}
    with common.client(endpoint, timeout) as world:
        budget = timeout + (_wall_bound(world, goal_timeout) if wait else 0.0)
        reply = world.call("goto", timeout=budget, **{k: v for k, v in fields.items() if v is not None})
    if json_:
        common.json_out(env, reply)
    common.checked(reply)
    if not wait:
        if not json_:
            common.say(env, f"'{name}': driving to ({x:g}, {y:g}) from step {reply['step']}")
        return ExitCode.OK
    if not json_:
        pose = common.pose_text(reply["pose"]) if reply.get("pose") else "deleted"
        error = f"{reply['error']:.3f} m" if reply.get("error") is not None else "unknown distance"
        common.say(env, f"t={reply['t']:.3f} {name}: {reply['status']} after {reply['time']:.3f} s, "
                        f"{error} from the goal; {pose}" + (f" ({reply['reason']})" if reply.get("reason") else ""))
    return ExitCode.OK if reply["status"] == "reached" else ExitCode.EXPECTATION_FAILED


def _wall_bound(world, seconds: Optional[float]) -> float:
    """How long S simulated seconds take on the wall clock at this world's pace."""
    if seconds is None:
        return WAIT_WITHOUT_TIMEOUT
    rtf = common.checked(world.call("ping")).get("rtf")
    return seconds / rtf if rtf else seconds
