"""All terminal output of mobot: errors, notices, tables and progress. Rich lives only here."""

from __future__ import annotations

import json
import sys
from dataclasses import dataclass
from typing import Any, Iterable

from mobot_cli.errors import MobotError


@dataclass
class _State:
    traceback: bool = False


STATE = _State()


def report_error(exc: MobotError) -> None:
    """One short paragraph on stderr, no traceback."""
    sys.stderr.write(f"mobot: error: {exc}\n")


def notices(lines: Iterable[str], quiet: bool = False) -> None:
    """Print warnings that did not stop the command."""
    if quiet:
        return
    for line in lines:
        sys.stderr.write(f"mobot: warning: {line}\n")


def emit_json(data: Any) -> None:
    """Print a JSON document on stdout, for scripts."""
    sys.stdout.write(json.dumps(data, indent=2) + "\n")


def stdout_console():
    """A Rich console on stdout (imported lazily: Rich is not needed for --help or --json)."""
    from rich.console import Console

    return Console(highlight=False)


def progress_bar(total: int, label: str):
    """A Rich progress bar on stderr when it is a terminal; otherwise None."""
    if not sys.stderr.isatty():
        return None
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

    bar = Progress(TextColumn("{task.description}"), BarColumn(), TextColumn("{task.percentage:>3.0f}%"),
                   TimeRemainingColumn(), console=Console(stderr=True), transient=True)
    bar.add_task(label, total=total)
    return bar


def run_table(summary: dict[str, Any], out_dir) -> None:
    """The per-robot table printed after a run."""
    from rich.table import Table

    table = Table(title=f"{summary['scenario']}: {summary['sim_time']:g} s simulated in "
                        f"{summary['wall_time']:g} s ({summary['real_time_factor']}x real time)")
    for column in ("robot", "distance m", "final x", "final y", "final yaw", "odom error m"):
        table.add_column(column, justify="left" if column == "robot" else "right")
    for name, robot in summary["robots"].items():
        pose = robot["final_pose"]
        table.add_row(name, f"{robot['distance']:.3f}", f"{pose['x']:.3f}", f"{pose['y']:.3f}",
                      f"{pose['yaw']:.3f}", f"{robot['odom_error']['position']:.3f}")
    console = stdout_console()
    console.print(table)
    console.print(f"run folder: {out_dir}")


def check_result(result: dict[str, Any]) -> None:
    """One line saying what was checked and that it is fine."""
    if result["kind"] == "scenario":
        line = (f"ok: scenario '{result['name']}': {len(result['robots'])} robot(s), "
                f"{result['duration']:g} s ({result['steps']} steps)")
    else:
        line = f"ok: robot '{result.get('name', result['path'])}' ({result['path']})"
    sys.stdout.write(line + "\n")


def inspect_tree(summary: dict[str, Any]) -> None:
    """The link/joint tree, mass, footprint and drive of a robot, as a Rich tree."""
    from rich.tree import Tree

    def add(branch, node: dict[str, Any]) -> None:
        for child in node["children"]:
            label = f"{child['link']}  [dim]({child['type']} joint {child['joint']}, {child['mass']:g} kg)[/]"
            add(branch.add(label), child)

    root = summary["tree"]
    tree = Tree(f"[bold]{root['link']}[/]  [dim]({root['mass']:g} kg)[/]")
    add(tree, root)
    console = stdout_console()
    console.print(f"[bold]{summary['name']}[/]  {summary['source']}")
    console.print(tree)
    fp = summary["footprint"]
    console.print(f"total mass {summary['total_mass']:.3f} kg; footprint {fp['length']:.3f} x {fp['width']:.3f} m "
                  f"(x {fp['xmin']:.3f}..{fp['xmax']:.3f}, y {fp['ymin']:.3f}..{fp['ymax']:.3f})")
    drive = summary["drive"]
    if drive is None:
        console.print("drive: none detected (set drive: in the scenario to command this robot)")
        return
    console.print(f"drive ({drive['source']}): left {', '.join(drive['left_joints'])}; right "
                  f"{', '.join(drive['right_joints'])}; wheel radius {drive['wheel_radius']:.4f} m, separation "
                  f"{drive['wheel_separation']:.4f} m x {drive['wheel_separation_multiplier']:g}; "
                  f"max torque {drive['max_wheel_torque']:g} N*m")
