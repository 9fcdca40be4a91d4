"""`mobot sweep SCENARIO`: many variants of one scenario, one row each in results.csv."""

from __future__ import annotations

import os
import time
from pathlib import Path
from typing import Optional

import typer

from mobot_cli.cli import output
from mobot_cli.cli.args import default_out
from mobot_cli.errors import ExitCode, Location, UsageError

EXECUTORS = ("local", "ray")


def sweep(
    ctx: typer.Context,
    path: Path = typer.Argument(..., help="A scenario, or a sweep file (YAML naming a base 'scenario:' and "
                                          "grid/zip/random)."),
    grid: list[str] = typer.Option([], "--grid",
                                   help="KEY=V1,V2,...: one axis; several --grid make every combination."),
    zip_: list[str] = typer.Option([], "--zip",
                                   help="KEY=V1,V2,...: lists paired by position; all --zip form one axis."),
    random: list[str] = typer.Option([], "--random", help="KEY=LOW:HIGH: uniform draws (whole numbers when both "
                                                          "ends are); all --random form one axis."),
    samples: Optional[int] = typer.Option(None, "--samples", help="How many random draws."),
    seed: Optional[int] = typer.Option(None, "--seed", help="Sweep seed; draws and each run's seed derive from it "
                                                            "[default: the scenario's seed]."),
    set_: list[str] = typer.Option([], "--set", help="Override a key in every run (repeatable)."),
    jobs: Optional[int] = typer.Option(None, "--jobs", "-j", help="Runs at a time [default: the number of cores]."),
    executor: str = typer.Option("local", "--executor", help="Where runs run: local (a process pool) or ray."),
    address: Optional[str] = typer.Option(None, "--address", help="Ray cluster address [default: a local Ray]."),
    timeout: Optional[float] = typer.Option(None, "--timeout", help="Fail a run after this many wall-clock seconds."),
    out: Optional[Path] = typer.Option(None, "--out", "-o", help="Sweep folder [default: sweeps/<name>-<time>]."),
    resume: bool = typer.Option(False, "--resume", help="Finish the sweep in --out, skipping runs in results.csv."),
    json_: bool = typer.Option(False, "--json", help="Print sweep.json and every row as JSON on stdout."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="Print nothing but errors."),
    pictures: bool = typer.Option(False, "--pictures", help="Draw each run's trajectory.png (`mobot plot RUN_DIR` "
                                  "draws any run folder later)."),
    junit: Optional[Path] = typer.Option(None, "--junit", help="Also write a JUnit XML report: a testcase per run, "
                                         "its seed, swept values and metrics as properties."),
) -> int:
    """Run variants of a scenario (grid, zip or random values); exit 1 when any run fails."""
    env = ctx.obj
    jobs = _check_args(jobs, executor, address, timeout, out, resume)
    runner = _executor(executor, jobs, timeout, address, pictures)
    # The fork server, then the workers, start now: their imports take the second core while
    # this process imports the scenario models and prepares the runs.
    runner.prestart()
    try:
        from mobot_cli.sweep.spec import build_spec, run_count

        spec = build_spec(path, grid, zip_, random, samples, seed, set_)
        runner.prestart(run_count(spec))
        from mobot_cli.sweep.execution import check_out_dir
        from mobot_cli.sweep.expand import expand

        prepared = expand(spec)  # every run prepared (and so checked) before any starts
        from mobot_cli.common import cache

        output.notices(env, [cache.warning()] if cache.warning() else [], quiet=quiet or json_)  # once, not per run
        out_dir = out or default_out("sweeps", prepared.name)
        done = check_out_dir(prepared, out_dir, resume)
        runner.start()  # e.g. join the Ray cluster: a failure here leaves no sweep folder behind
        started = time.perf_counter()
        report = _run(env, runner, prepared, out_dir, done, quiet or json_, pictures)
    finally:
        runner.close()
    total = len(prepared.variants)
    rows = [r for _, r in sorted(report.rows.items())]
    if junit is not None:
        from mobot_cli.record import junit as junit_xml

        junit_xml.write(junit, junit_xml.sweep_suites(rows, out_dir, prepared.name))
    if json_:
        output.emit_json(env, {**report.document, "results": rows})
    elif quiet:
        output.sweep_failures(env, out_dir, len(report.failed), total)
    else:
        output.sweep_summary(env, out_dir, rows, list(prepared.keys), total, report.skipped,
                             time.perf_counter() - started, report.document.get("goals"))
    return ExitCode.EXPECTATION_FAILED if report.failed else ExitCode.OK


def _run(env, runner, prepared, out_dir: Path, done: dict, silent: bool, pictures: bool = False):
    """The runs, with a progress bar unless ``silent``; Ctrl-C says where the finished rows are."""
    from mobot_cli.sweep.execution import run_sweep

    bar = None if silent else output.sweep_progress(env, len(prepared.variants), prepared.name)
    if bar:
        bar.start()
    try:
        return run_sweep(prepared, out_dir, runner, done, progress=output.sweep_updates(bar), pictures=pictures)
    except KeyboardInterrupt:
        if bar:
            bar.stop()
        output.sweep_interrupted(env, out_dir)
        raise
    finally:
        if bar:
            bar.stop()


def _check_args(jobs: int | None, executor: str, address: str | None, timeout: float | None,
                out: Path | None, resume: bool) -> int:
    if executor not in EXECUTORS:
        raise UsageError(f"unknown executor '{executor}'", location=Location(file="--executor"),
                         hint="Use local or ray.")
    if address and executor != "ray":
        raise UsageError("--address is for --executor ray", hint="Add --executor ray, or drop --address.")
    if jobs is not None and jobs < 1:
        raise UsageError(f"--jobs must be at least 1, got {jobs}")
    if timeout is not None and not timeout > 0:
        raise UsageError(f"--timeout must be above 0 seconds, got {timeout:g}")
    if resume and out is None:
        raise UsageError("--resume needs --out, the folder of the sweep to finish")
    return jobs or os.cpu_count() or 1


def _executor(name: str, jobs: int, timeout: float | None, address: str | None, pictures: bool = False):
    if name == "ray":
        from mobot_cli.sweep.executor_ray import RayExecutor, require_ray

        require_ray()  # a missing extra is bad input: say so before preparing runs
        return RayExecutor(jobs, timeout, address)
    from mobot_cli.sweep.executor_local import LocalExecutor

    return LocalExecutor(jobs, timeout, pictures=pictures)
