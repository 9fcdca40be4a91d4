"""`mobot scan NAME [--sensor S] [--follow]`: a robot's latest sensor reading in the live world."""

from __future__ import annotations

import math
from typing import Any, Optional

import typer

from mobot_cli.cli.live import common


def scan(
    ctx: typer.Context,
    name: str = typer.Argument(..., help="The robot to read."),
    sensor: Optional[str] = typer.Option(None, "--sensor", "-s",
                                         help="Its sensor [default: its first lidar, else its first sensor]."),
    follow: bool = typer.Option(False, "--follow", "-f", help="Print every new reading until Ctrl-C."),
    rate: float = typer.Option(10.0, "--rate", help="Polls per second (wall clock) with --follow."),
    endpoint: common.Endpoint = None,
    timeout: common.Timeout = 5.0,
    json_: common.JsonLines = False,
) -> int:
    """Print a robot's latest lidar scan (or range, IMU or contact reading) from the live world."""
    env = ctx.obj
    fields = {"name": name, **({"sensor": sensor} if sensor else {})}
    with common.client(endpoint, timeout) as world:
        return common.read_or_follow(env, world, "scan", fields, reading_line, follow, rate, json_)


def reading_line(reply: dict[str, Any]) -> str:
    """One reading in a line: a lidar's returns and nearest one, a range, an IMU's values, contacts."""
    head = f"t={reply['t']:.3f} {reply['name']}/{reply['sensor']} ({reply['kind']}, {reply['topic']})"
    if reply["kind"] == "lidar":
        return f"{head} {_lidar(reply)}"
    if reply["kind"] == "range":
        return (f"{head} {reply['range']:.3f} m ({reply['radiation_type']}, "
                f"{reply['min_range']:g}..{reply['max_range']:g} m)")
    if reply["kind"] == "imu":
        w, a = reply["angular_velocity"], reply["linear_acceleration"]
        return (f"{head} accel {' '.join(f'{v:.3f}' for v in a)} m/s^2, "
                f"gyro {' '.join(f'{v:.3f}' for v in w)} rad/s")
    contacts = reply["contacts"]
    if not contacts:
        return f"{head} no contact"
    others = sorted({c["other"] for c in contacts})
    force = sum(c["force"] for c in contacts)
    return f"{head} {len(contacts)} contact point(s) with {', '.join(others)}, {force:.2f} N"


def _lidar(reply: dict[str, Any]) -> str:
    rows = reply["ranges"] if reply["ranges"] and isinstance(reply["ranges"][0], list) else [reply["ranges"]]
    row = rows[len(rows) // 2]  # the middle row, as a LaserScan of a 3D lidar
    beams = len(row)
    found = [(r, i) for i, r in enumerate(row) if r is not None]
    shape = f"{beams} beams" if len(rows) == 1 else f"{len(rows)} x {beams} beams (middle row)"
    span = f"{math.degrees(reply['angle_min']):.1f}..{math.degrees(reply['angle_max']):.1f} deg"
    if not found:
        return f"{shape} over {span}: no return within {reply['range_max']:g} m"
    nearest, index = min(found)
    angle = reply["angle_min"] + index * reply["angle_increment"]
    return (f"{shape} over {span}: {len(found)} returns, nearest {nearest:.3f} m at "
            f"{math.degrees(angle):.1f} deg")
