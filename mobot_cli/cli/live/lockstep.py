"""Lockstep control of the live world, as ROS 2's simulation_interfaces offers it:
`mobot pause`, `resume`, `step [N] [--seconds S]`, `reset`, `state NAME`, `teleport NAME ...`
and `features`. Each sends one request and prints its reply (``--json``: the reply itself)."""

from __future__ import annotations

import math
from typing import Annotated, Any, Optional

import typer

from mobot_cli.cli.live import common
from mobot_cli.errors import ExitCode, UsageError

ReferenceFrame = Annotated[Optional[str], typer.Option(
    "--reference-frame", metavar="ENTITY", help="Give pose and twist relative to this robot [default: world].")]


def pause(ctx: typer.Context, endpoint: common.Endpoint = None, timeout: common.Timeout = 5.0,
          json_: common.Json = False) -> int:
    """Pause the live world: it answers requests but takes no step until `mobot step` or `mobot resume`."""
    return _send(ctx.obj, endpoint, timeout, json_, "pause", {}, _state_line)


def resume(ctx: typer.Context, endpoint: common.Endpoint = None, timeout: common.Timeout = 5.0,
           json_: common.Json = False) -> int:
    """Let a paused live world play on at its pace."""
    return _send(ctx.obj, endpoint, timeout, json_, "resume", {}, _state_line)


def step(
    ctx: typer.Context,
    steps: Optional[int] = typer.Argument(None, metavar="[N]", help="Physics steps to take [default: 1]."),
    seconds: Optional[float] = typer.Option(None, "--seconds", "-s", metavar="S",
                                            help="Simulated seconds instead: a whole number of steps."),
    endpoint: common.Endpoint = None,
    timeout: common.Timeout = 60.0,
    json_: common.Json = False,
) -> int:
    """Advance a paused world exactly N steps (or S seconds) as fast as it can; prints where it got."""
    if steps is not None and seconds is not None:
        raise UsageError("give N steps or --seconds S, not both")
    if seconds is not None and not math.isfinite(seconds):
        raise UsageError(f"--seconds {seconds} is not a finite number of seconds")
    fields: dict[str, Any] = {"steps": steps} if steps is not None else {}
    if seconds is not None:
        fields["seconds"] = seconds
    return _send(ctx.obj, endpoint, timeout, json_, "step", fields, _step_lines)


def reset(ctx: typer.Context, endpoint: common.Endpoint = None, timeout: common.Timeout = 5.0,
          json_: common.Json = False) -> int:
    """Put the world back as it started, at t = 0: the scenario's robots at their poses, scripts from the top."""
    return _send(ctx.obj, endpoint, timeout, json_, "reset", {},
                 lambda r: [f"reset to t=0.000 ({r['state']}); robots: {', '.join(r['robots']) or 'none'}"])


def state(
    ctx: typer.Context,
    name: str = typer.Argument(..., help="The robot to read."),
    reference_frame: ReferenceFrame = None,
    endpoint: common.Endpoint = None,
    timeout: common.Timeout = 5.0,
    json_: common.Json = False,
) -> int:
    """Print a robot's ground-truth pose and twist (GetEntityState)."""
    fields = {"name": name, **({"reference_frame": reference_frame} if reference_frame is not None else {})}
    return _send(ctx.obj, endpoint, timeout, json_, "get_state", fields, lambda r: [_entity_line(r)])


def teleport(
    ctx: typer.Context,
    name: str = typer.Argument(..., help="The robot to move."),
    x: common.X = 0.0,
    y: common.Y = 0.0,
    z: common.Z = None,
    roll: common.Roll = 0.0,
    pitch: common.Pitch = 0.0,
    yaw: common.Yaw = 0.0,
    quat: common.Quat = None,
    linear: tuple[float, float, float] = typer.Option((0.0, 0.0, 0.0), "--linear", metavar="VX VY VZ",
                                                      help="Linear velocity afterwards, m/s [default: at rest]."),
    angular: tuple[float, float, float] = typer.Option((0.0, 0.0, 0.0), "--angular", metavar="WX WY WZ",
                                                       help="Angular velocity afterwards, rad/s."),
    reference_frame: ReferenceFrame = None,
    endpoint: common.Endpoint = None,
    timeout: common.Timeout = 5.0,
    json_: common.Json = False,
) -> int:
    """Move a robot to a pose (SetEntityState), checked for collisions like a spawn."""
    pose = common.requested_pose(x, y, z, roll, pitch, yaw, quat)
    numbers = [x, y, roll, pitch, yaw, *(quat or ()), *linear, *angular, *(() if z is None else (z,))]
    if not all(math.isfinite(v) for v in numbers):
        raise UsageError("teleport takes finite numbers: NaN and infinity are not a pose or a twist")
    fields: dict[str, Any] = {"name": name, "pose": pose, "twist": {"linear": dict(zip("xyz", linear)),
                                                                      "angular": dict(zip("xyz", angular))}}
    if reference_frame is not None:
        fields["reference_frame"] = reference_frame
    return _send(ctx.obj, endpoint, timeout, json_, "set_state", fields, lambda r: ["teleported " + _entity_line(r)])


def features(ctx: typer.Context, endpoint: common.Endpoint = None, timeout: common.Timeout = 5.0,
             json_: common.Json = False) -> int:
    """List what the live world supports (GetSimulatorFeatures): ids and names, and its requests."""
    return _send(ctx.obj, endpoint, timeout, json_, "features", {}, lambda r: [
        *(f"{f['id']:>3}  {f['name']}" for f in r["features"]),
        f"spawn formats: {', '.join(r['spawn_formats'])}", f"requests: {', '.join(r['ops'])}"])


def _send(env, endpoint, timeout, json_, op, fields, lines) -> int:
    with common.client(endpoint, timeout) as world:
        reply = world.call(op, **fields)
    if json_:
        common.json_out(env, reply)
    common.checked(reply)
    if not json_:
        for line in lines(reply):
            common.say(env, line)
    return ExitCode.OK


def _state_line(reply: dict[str, Any]) -> list[str]:
    was = "" if reply["changed"] else " (already)"
    return [f"{reply['state']}{was} at t={reply['t']:.3f} s (step {reply['step']})"]


def _step_lines(reply: dict[str, Any]) -> list[str]:
    lines = [f"stepped {reply['steps']} to t={reply['t']:.3f} s (step {reply['step']})"]
    return lines + ["  " + _entity_line(robot, t=False) for robot in reply.get("robots", [])]


def _entity_line(reply: dict[str, Any], t: bool = True) -> str:
    pose, twist = reply["pose"], reply["twist"]
    frame = reply.get("reference_frame", "world")
    v, w = twist["linear"], twist["angular"]
    when = f"t={reply['t']:.3f} " if t else ""
    return (f"{when}{reply['name']} in {frame}: {common.pose_text(pose)}  "
            f"linear {_v(v)}  angular {_v(w)}")


def _v(vector: dict[str, float]) -> str:
    return " ".join(f"{vector[k]:.3f}".replace("-0.000", "0.000") for k in "xyz")
