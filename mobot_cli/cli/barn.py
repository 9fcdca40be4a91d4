"""`mobot barn DIR`: the BARN benchmark's worlds, run and scored as the BARN challenge does."""

from __future__ import annotations

import os
import time
from pathlib import Path
from typing import Optional

import typer

from mobot_cli.cli import output
from mobot_cli.cli.args import default_out
from mobot_cli.errors import ExitCode, Location, UsageError


def barn(
    ctx: typer.Context,
    folder: Path = typer.Argument(..., help="The folder of BARN's world_N.world and path_files/ (or a clone of "
                                            "github.com/Daffan/the-barn-challenge)."),
    worlds: str = typer.Option("0-299", "--worlds", help="World numbers: 0-299, 0,6,12 or 0-9,100."),
    engine: str = typer.Option("kinematic", "--engine", help="kinematic (robots follow their twist) or bullet."),
    robot: str = typer.Option("jackal_like", "--robot", help="The robot: a bundled name or a .urdf/.xacro path; "
                                                             "it needs its own 2D lidar for --local."),
    max_linear: float = typer.Option(0.5, "--max-linear", help="Top speed, m/s (BARN's DWA baseline: 0.5)."),
    max_angular: float = typer.Option(1.57, "--max-angular", help="Top turn rate, rad/s (BARN's DWA: 1.57)."),
    planner: Optional[str] = typer.Option(None, "--planner", help="The goal's global planner (e.g. astar), where "
                                                                  "this mobot's goals take one."),
    local: Optional[str] = typer.Option(None, "--local", help="The goal's local controller (e.g. dwb), where this "
                                                              "mobot's goals take one."),
    lidar: bool = typer.Option(True, "--lidar/--no-lidar", help="Keep the robot's 2D lidar (scan) on; it is "
                                                                 "recorded in every run folder (3.2 MB a world)."),
    jobs: Optional[int] = typer.Option(None, "--jobs", "-j", help="Runs at a time [default: the number of cores]."),
    out: Optional[Path] = typer.Option(None, "--out", "-o", help="Output folder [default: barn/barn-<time>]."),
    json_: bool = typer.Option(False, "--json", help="Print barn.json on stdout."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="Print nothing but errors."),
) -> int:
    """Run BARN's worlds start to goal and score them (success, collision, timeout, time, score)."""
    env = ctx.obj
    from mobot_cli.scenario.limits import ENGINES

    if engine not in ENGINES:
        raise UsageError(f"unknown engine '{engine}'", location=Location(file="--engine"),
                         hint="Use kinematic or bullet.")
    if jobs is not None and jobs < 1:
        raise UsageError(f"--jobs must be at least 1, got {jobs}")
    from mobot_cli.sweep.barn import check_passed_through
    from mobot_cli.sweep.barn_worlds import Driver, find_folder, load_worlds, parse_numbers

    for flag, value in (("--max-linear", max_linear), ("--max-angular", max_angular)):
        if not value > 0:
            raise UsageError(f"must be above 0, got {value:g}", location=Location(file=flag))
    if robot.endswith((".urdf", ".xacro", ".sdf")) or "/" in robot:  # a file: from here, not from --out
        robot = str(Path(robot).expanduser().resolve())
    extra = check_passed_through({"planner": planner, "local": local})
    numbers = parse_numbers(worlds)
    barn_dir = find_folder(folder)
    out_dir = out or default_out("barn", "barn")
    _check_out(out_dir)
    from mobot_cli.sweep.barn import run_barn_task
    from mobot_cli.sweep.executor_local import LocalExecutor

    runner = LocalExecutor(jobs or os.cpu_count() or 1, None, runner=run_barn_task)
    runner.prestart()
    try:
        chosen = load_worlds(barn_dir, numbers)
        from mobot_cli.sweep.barn import SWEEP, collect, prepare_sweep

        sweep = prepare_sweep(out_dir, chosen, Driver(robot, engine, max_linear, max_angular, extra, lidar))
        runner.prestart(len(sweep.variants))
        runner.start()
        started = time.perf_counter()
        from mobot_cli.sweep.execution import run_sweep

        bar = None if quiet or json_ else output.sweep_progress(env, len(sweep.variants), "barn")
        if bar:
            bar.start()
        try:
            done = run_sweep(sweep, out_dir / SWEEP, runner, {}, progress=output.sweep_updates(bar))
        finally:
            if bar:
                bar.stop()
    finally:
        runner.close()
    report = collect(out_dir, sweep, chosen, done.rows)
    wall = time.perf_counter() - started
    if json_:
        env.stdout.write((out_dir / "barn.json").read_text(encoding="utf-8"))
    elif not quiet:
        _print(env, report, wall)
    if report.failed_runs:
        env.stderr.write(f"mobot: {report.failed_runs} of {len(report.outcomes)} runs did not finish; "
                         f"see {out_dir}/barn.csv\n")
        return ExitCode.EXPECTATION_FAILED
    return ExitCode.OK


def _check_out(out_dir: Path) -> None:
    from mobot_cli.common.files import check_out_folder

    check_out_folder(out_dir)
    if out_dir.exists() and (not out_dir.is_dir() or any(out_dir.iterdir())):
        raise UsageError(f"{out_dir} is not empty", location=Location(file="--out"),
                         hint="Choose a new or empty folder for --out.")


def _print(env, report, wall: float) -> None:
    from rich.table import Table

    console = output.stdout_console(env)
    if len(report.outcomes) <= 20:
        table = Table(title="BARN worlds")
        for column in ("world", "status", "time (s)", "optimal (s)", "score"):
            table.add_column(column, justify="left" if column == "status" else "right")
        for o in report.outcomes:
            table.add_row(str(o.world), o.status, f"{o.time:.2f}", f"{o.optimal_time:.2f}", f"{o.score:.4f}")
        console.print(table)
    s = report.summary
    table = Table(title=f"BARN: {s['worlds']} worlds")
    for column in ("success", "collision", "timeout", "mean time (s)", "mean score"):
        table.add_column(column, justify="right")
    mean_time = "-" if s["mean_time"] is None else f"{s['mean_time']:.2f}"
    table.add_row(f"{s['success_rate']:.3f}", f"{s['collision_rate']:.3f}", f"{s['timeout_rate']:.3f}", mean_time,
                  f"{s['mean_score']:.4f}")
    console.print(table)
    console.print(f"mean time over successful runs; {len(report.outcomes)} runs in {wall:.1f} s", highlight=False)
    console.print(f"results: {report.out_dir}/barn.csv, barn.json", highlight=False)
