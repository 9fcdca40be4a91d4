"""`mobot run SCENARIO...`: run scenarios to their end and write a run folder for each."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from mobot_cli.cli import ros2


def run(
    ctx: typer.Context,
    scenario: list[Path] = typer.Argument(..., help="The scenario YAML file(s), run one after another."),
    out: Optional[Path] = typer.Option(None, "--out", "-o",
                                       help="Run folder [default: runs/<name>-<time>]; with several files, "
                                            "DIR/<file name without .yaml> for each."),
    set_: list[str] = typer.Option([], "--set", help="Override a key, e.g. robots.mobot.pose.x=2.0 (repeatable)."),
    seed: Optional[int] = typer.Option(None, "--seed", help="Override the scenario's seed."),
    duration: Optional[float] = typer.Option(None, "--duration", help="Override the duration, in seconds."),
    realtime: bool = typer.Option(False, "--realtime", help="Pace the run to the wall clock."),
    json_: bool = typer.Option(False, "--json", help="Print summary.json on stdout; with several files, each "
                                                     "summary on one line (JSON Lines)."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="Print nothing but errors."),
    skip_missing: bool = typer.Option(False, "--skip-missing",
                                      help="Leave out world models and robot visuals/collisions whose files "
                                           "are missing, with a warning."),
    ros2_: bool = typer.Option(False, "--ros2", help=ros2.HELP),
    view: bool = typer.Option(False, "--view", help="Watch the run in a local 3D web page (extra 'view'); "
                              "when it ends the page replays it until Ctrl-C. One file only."),
    view_port: int = typer.Option(8080, "--view-port", help="Port of the --view page on 127.0.0.1 (0: any)."),
) -> int:
    """Run scenarios to their end and write odometry, a summary and the resolved scenario of each.

    Several files run one after another in this one process, each into its own run folder; a
    file that fails is reported and the next one runs. The exit code is the worst of the runs':
    0 ok < 1 an expectation failed < 2 bad input < 3 simulation fault. Ctrl-C (130) stops them
    all at once.
    """
    from mobot_cli.cli.runner import RunOptions, run_scenarios

    options = RunOptions(set_, seed, duration, realtime, json_, quiet, skip_missing, ros2_, view, view_port)
    return run_scenarios(ctx.obj, scenario, out, options)
