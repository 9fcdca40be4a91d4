"""`mobot spawn NAME`: spawn a robot into the live world, with spawn_entity.py's flags."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from mobot_cli.cli import output
from mobot_cli.cli.args import parse_mappings
from mobot_cli.cli.live import common
from mobot_cli.errors import ExitCode, UsageError


def spawn(
    ctx: typer.Context,
    name: str = typer.Argument(..., help="The robot's name (unique in the world)."),
    mappings: list[str] = typer.Argument(None, metavar="[NAME:=VALUE]...", help="xacro arguments."),
    file: Optional[str] = typer.Option(
        None, "--file", "-f",
        help="A .urdf/.xacro path, an SDF model (.sdf, model folder, model://NAME) or a bundled robot name."),
    string: Optional[str] = typer.Option(None, "--string", help="The URDF, xacro or SDF model text itself."),
    stdin: bool = typer.Option(False, "--stdin", help="Read the URDF, xacro or SDF model text from standard input."),
    x: common.X = 0.0,
    y: common.Y = 0.0,
    z: common.Z = None,
    roll: common.Roll = 0.0,
    pitch: common.Pitch = 0.0,
    yaw: common.Yaw = 0.0,
    quat: common.Quat = None,
    namespace: Optional[str] = typer.Option(None, "--namespace", help="ROS namespace [default: /NAME]."),
    reference_frame: Optional[str] = typer.Option(None, "--reference-frame", metavar="ENTITY",
                                                  help="Give the pose relative to this robot [default: world]."),
    allow_renaming: bool = typer.Option(False, "--allow-renaming",
                                        help="If NAME is taken, use NAME_0, NAME_1, ... instead of failing."),
    endpoint: common.Endpoint = None,
    timeout: common.Timeout = 30.0,
    json_: common.Json = False,
) -> int:
    """Spawn a robot; the reply comes once it exists and passed the collision check."""
    env = ctx.obj
    sources = [s for s in (file is not None, string is not None, stdin) if s]
    if len(sources) != 1:
        raise UsageError("give exactly one of --file, --string and --stdin",
                         hint="For example: mobot spawn r1 --file mobot -x 1.0 -y 2.0")
    pose = common.requested_pose(x, y, z, roll, pitch, yaw, quat)
    text = env.stdin.read() if stdin else string
    fields = {"description": file, "urdf": text, "pose": pose, "args": parse_mappings(mappings or []),
              "namespace": namespace, "reference_frame": reference_frame, "allow_renaming": allow_renaming,
              "base_dir": str(Path.cwd())}
    with common.client(endpoint, timeout) as world:
        reply = world.call("spawn", name=name, **{k: v for k, v in fields.items() if v is not None})
    if json_:
        common.json_out(env, reply)
    common.checked(reply)
    output.notices(env, reply.get("notices", []), quiet=json_)
    if not json_:
        renamed = f" (renamed from '{name}')" if reply["renamed"] else ""
        common.say(env, f"spawned '{reply['name']}'{renamed} in {reply['namespace']} at "
                        f"{common.pose_text(reply['pose'])}, t={reply['t']:.3f} s")
    return ExitCode.OK
