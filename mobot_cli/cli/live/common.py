"""What the live-world commands share: their common options (endpoint, timeout, --json, a pose),
the client, the printing.

Plain text only (no Rich), so `mobot list` and `mobot odom` answer fast.
"""

from __future__ import annotations

import json
import time
from typing import Annotated, Any, Callable, Optional

import typer

from mobot_cli.cli.environment import Environment
from mobot_cli.errors import ExitCode, RequestRefused, UsageError

# The options the live clients share, as types: a command declares one as `endpoint: Endpoint = None`,
# its default in its own signature (Typer reads the flag and help from the Annotated metadata).
TIMEOUT_HELP = "Seconds to wait for the reply (exit 4 when nothing answers)."
ENDPOINT_HELP = ("Where the live world listens [default: $MOBOT_ENDPOINT, else "
                 "ipc://$XDG_RUNTIME_DIR/mobot/mobot.sock].")
Endpoint = Annotated[Optional[str], typer.Option("--endpoint", "-e", metavar="ENDPOINT", help=ENDPOINT_HELP)]
Timeout = Annotated[float, typer.Option("--timeout", help=TIMEOUT_HELP)]
Json = Annotated[bool, typer.Option("--json", help="Print the reply as JSON.")]
JsonLines = Annotated[bool, typer.Option("--json", help="Print replies as JSON (one line each with --follow).")]

# A pose as spawn_entity.py takes it: shared by `mobot spawn` and `mobot teleport`.
X = Annotated[float, typer.Option("-x", help="Position, m.")]
Y = Annotated[float, typer.Option("-y", help="Position, m.")]
Z = Annotated[Optional[float], typer.Option("-z", help="Height, m [default: rest on the floor].")]
Roll = Annotated[float, typer.Option("-R", help="Roll, rad.")]
Pitch = Annotated[float, typer.Option("-P", help="Pitch, rad.")]
Yaw = Annotated[float, typer.Option("-Y", help="Yaw, rad.")]
Quat = Annotated[Optional[tuple[float, float, float, float]], typer.Option(
    "--quat", metavar="X Y Z W", help="Orientation as a quaternion instead of -R -P -Y.")]


def requested_pose(x: float, y: float, z: Optional[float], roll: float, pitch: float, yaw: float,
                   quat: Optional[tuple[float, float, float, float]]) -> dict:
    """The request's pose from the pose options (z None: rest on the floor); UsageError for both
    a quaternion and roll/pitch/yaw."""
    if quat is not None and (roll or pitch or yaw):
        raise UsageError("give the orientation either as --quat or as -R -P -Y, not both")
    pose: dict = {"xyz": [x, y, "auto" if z is None else z]}
    pose.update({"quat": list(quat)} if quat is not None else {"rpy": [roll, pitch, yaw]})
    return pose


def client(endpoint: Optional[str], timeout: float):
    """A Client of the live world (ZeroMQ is imported only when a command runs)."""
    from mobot_cli.live.client import Client

    return Client(endpoint, timeout=timeout)


def checked(reply: dict[str, Any]) -> dict[str, Any]:
    """The reply, or RequestRefused (exit 2) printing its result code and message."""
    if not reply.get("ok"):
        raise RequestRefused(str(reply.get("result")), str(reply.get("message")))
    return reply


def json_out(env: Environment, reply: Any) -> None:
    """A reply as JSON on stdout (printed for refused requests too, before the error)."""
    from mobot_cli.cli.output import emit_json

    emit_json(env, reply)


def say(env: Environment, line: str) -> None:
    """One line on stdout, flushed (odom --follow and scripts read it as it comes)."""
    env.stdout.write(line + "\n")
    env.stdout.flush()


def status(env: Environment, line: str) -> None:
    """One line on stderr: what the server is doing (stdout stays for data)."""
    env.stderr.write(f"mobot: {line}\n")
    env.stderr.flush()


def pose_text(pose: dict[str, Any]) -> str:
    """x=.. y=.. z=.. yaw=.. of a reply's pose."""
    return " ".join(f"{k}={_f(pose.get(k))}" for k in ("x", "y", "z", "yaw"))


def robot_table(env: Environment, robots: list[dict[str, Any]]) -> None:
    """The robots of `mobot list`, one line each under a header."""
    if not robots:
        say(env, "no robots in the live world")
        return
    rows = [("NAME", "NAMESPACE", "X", "Y", "Z", "YAW", "LINEAR", "ANGULAR")]
    for robot in robots:
        pose, cmd = robot["pose"], robot["cmd"]
        rows.append((robot["name"], robot["namespace"] or "", *(_f(pose.get(k)) for k in ("x", "y", "z", "yaw")),
                     _f(cmd["linear"]), _f(cmd["angular"])))
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    for row in rows:
        say(env, "  ".join(cell.ljust(w) if i < 2 else cell.rjust(w)
                      for i, (cell, w) in enumerate(zip(row, widths))).rstrip())


def odom_line(reply: dict[str, Any]) -> str:
    """One odometry reading: time, odom (spawn-pose frame), ground truth and command."""
    o, t, c = reply["odom"], reply["truth"], reply["cmd"]
    return (f"t={reply['t']:.3f} {reply['name']}  odom x={_f(o['x'])} y={_f(o['y'])} yaw={_f(o['yaw'])} "
            f"vx={_f(o['vx'])} wz={_f(o['wz'])}  true x={_f(t['x'])} y={_f(t['y'])} yaw={_f(t['yaw'])}  "
            f"cmd {_f(c['linear'])} {_f(c['angular'])}")


def _f(value: Any) -> str:
    return "nan" if value is None else f"{value:.3f}".replace("-0.000", "0.000")


def read_or_follow(env: Environment, world, op: str, fields: dict[str, Any], line: Callable[[dict], str],
                   follow: bool, rate: float, json_: bool) -> int:
    """Ask ``op`` once and print its reply; with ``follow``, poll at ``rate`` per second and print
    every reply of a new step (one JSON line each with ``json_``) until Ctrl-C or the robot goes."""
    reply = world.call(op, **fields)
    if not follow or not reply.get("ok"):
        if json_:
            json_out(env, reply)
        checked(reply)
        if not json_:
            say(env, line(reply))
        return ExitCode.OK
    rate, last = max(0.1, min(rate, 1000.0)), None
    try:
        while True:
            if not reply.get("ok"):
                status(env, f"'{fields['name']}' is gone: {reply.get('result')}: {reply.get('message')}")
                return ExitCode.OK
            if reply["step"] != last:
                last = reply["step"]
                say(env, json.dumps(reply) if json_ else line(reply))
            time.sleep(1.0 / rate)
            reply = world.call(op, **fields)
    except KeyboardInterrupt:
        return ExitCode.OK
