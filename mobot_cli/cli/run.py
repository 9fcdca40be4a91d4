"""`mobot run SCENARIO...`: run scenarios to their end and write a run folder for each.

`run` reads the command line; `run_scenarios` runs one scenario, or several one after another in
this process, each into its own run folder.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Optional, Sequence

import typer

from mobot_cli.cli import output, ros2
from mobot_cli.cli.args import default_out
from mobot_cli.cli.environment import Environment
from mobot_cli.cli.startup import collect_garbage
from mobot_cli.errors import ExitCode, MobotError, UsageError


@dataclass(frozen=True)
class RunOptions:
    """The options of `mobot run` that apply to each scenario it runs."""

    set_: Sequence[str] = ()
    seed: Optional[int] = None
    duration: Optional[float] = None
    realtime: bool = False
    json_: bool = False
    quiet: bool = False
    skip_missing: bool = False
    ros2_: bool = False
    view: bool = False
    view_port: int = 8080
    junit: Optional[Path] = None


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
    junit: Optional[Path] = typer.Option(None, "--junit", help="Also write a JUnit XML report: a testcase per "
                                         "expectation (or per run), metrics and seed as properties."),
) -> int:
    """Run scenarios to their end and write odometry, a summary and the resolved scenario of each.

    Several files run one after another in this one process, each into its own run folder; a
    file that fails is reported and the next one runs. The exit code is the worst of the runs':
    0 ok < 1 an expectation failed < 2 bad input < 3 simulation fault. Ctrl-C (130) stops them
    all at once.
    """
    options = RunOptions(set_, seed, duration, realtime, json_, quiet, skip_missing, ros2_, view, view_port, junit)
    return run_scenarios(ctx.obj, scenario, out, options)


def run_scenarios(env: Environment, scenarios: Sequence[Path], out: Optional[Path], options: RunOptions) -> int:
    """Run each scenario in turn; the worst exit code (ExitCode's order, 0 to 3).

    One scenario is `mobot run` as it always was: its errors raise. With several, a scenario
    that fails is reported and the next one runs; Ctrl-C stops them all at once (raised)."""
    suites: list = []  # --junit: a test suite per run, written once they are all done
    try:
        if len(scenarios) == 1:
            try:
                return run_scenario(env, scenarios[0], out, options, suites=suites)
            except MobotError as exc:
                _junit_refused(suites, 0, scenarios[0], exc)
                raise
        if options.view:
            raise UsageError("--view watches one run: give one scenario file", hint="or run them without --view")
        folders = _batch_folders(scenarios, out)
        worst = ExitCode.OK
        for scenario, folder in zip(scenarios, folders):
            before = len(suites)
            try:
                code = run_scenario(env, scenario, folder, options, one_line_json=True, suites=suites)
            except MobotError as exc:
                _junit_refused(suites, before, scenario, exc)
                if env.traceback:
                    raise
                output.report_error(env, exc)
                code = exc.exit_code
            worst = max(worst, code)
        return worst
    finally:
        if options.junit is not None:
            from mobot_cli.record import junit

            junit.write(options.junit, suites)


def _batch_folders(scenarios: Sequence[Path], out: Optional[Path]) -> list[Optional[Path]]:
    """Each scenario's run folder: OUT/<file stem> with --out, else its default (None)."""
    if out is None:
        return [None] * len(scenarios)
    seen: dict[str, Path] = {}
    for scenario in scenarios:
        other = seen.setdefault(scenario.stem, scenario)
        if other is not scenario:
            raise UsageError(f"'{other}' and '{scenario}' would both write {out / scenario.stem}: with several "
                             "scenario files, --out DIR writes DIR/<file name without .yaml> for each",
                             hint="rename one of them, or run them in two commands")
    return [out / scenario.stem for scenario in scenarios]


def run_scenario(env: Environment, scenario: Path, out: Optional[Path], options: RunOptions,
                 one_line_json: bool = False, suites: Optional[list] = None) -> int:
    """Run a scenario to its end, write the run folder and print what `mobot run` prints; the exit code.
    ``one_line_json``: --json prints the summary on one line (several runs: JSON Lines)."""
    from mobot_cli.common.files import check_out_folder
    from mobot_cli.run import execute
    from mobot_cli.scenario.prepare import prepare

    overrides = list(options.set_)
    if options.seed is not None:
        overrides.append(f"seed={options.seed}")
    if options.duration is not None:
        overrides.append(f"duration={options.duration}")
    if options.skip_missing:
        overrides.append("skip_missing=true")
    if options.view:
        from mobot_cli.view.page import require_viser

        require_viser()  # before the run, not after it
    done = prepare(scenario, overrides)
    collect_garbage()  # loaded: from here on garbage is made, and collected (cli/startup.py)
    plan = done.plan
    quiet = options.quiet or options.json_
    output.notices(env, plan.notices, quiet=quiet)
    bridges = ros2.bridges(plan, options.ros2_)
    out_dir = out or default_out("runs", plan.name)
    check_out_folder(out_dir)  # a file, a path under a file, a read-only folder: before the run
    bar = None if quiet else output.progress_bar(env, plan.total_steps, plan.name)
    progress = _progress(bar, options.realtime, plan.physics.rate_hz)
    ros2.joined(env, bridges, quiet=quiet)
    watcher = _Watcher(env, plan, options.view_port) if options.view else None
    if bar:
        bar.start()
    try:
        result = execute(plan, done.resolved_yaml, out_dir, progress=progress, attachments=bridges,
                         watch=watcher.watch if watcher else None)
    except BaseException:
        if watcher:
            watcher.close()
        if suites is not None and options.junit is not None:
            _junit_suite(suites, plan.name, out_dir, None)  # the fault or error summary.json records
        raise
    finally:
        if bar:
            bar.stop()
        ros2.report(env, bridges, quiet=quiet)
    if suites is not None and options.junit is not None:
        _junit_suite(suites, plan.name, out_dir, result.record)
    # Said during the run (stalled wheels, a car's clamped turn, odometry far from the truth): in summary.json too.
    output.notices(env, result.record.notices[len(plan.notices):], quiet=quiet)
    if options.json_:
        output.emit_json(env, result.record.to_dict(), one_line=one_line_json)
    elif not options.quiet:
        output.run_table(env, result.record, result.out_dir)
    output.expectations(env, result.expectations, verbose=not quiet)
    if watcher:
        watcher.replay(result.out_dir)
    if any(not r.passed for r in result.expectations):
        return ExitCode.EXPECTATION_FAILED
    return ExitCode.OK


def _junit_refused(suites: list, before: int, scenario: Path, exc: MobotError) -> None:
    """A run that left no record (bad input): its suite says the error."""
    if len(suites) == before:
        from mobot_cli.record import junit

        suites.append(junit.failed_suite(scenario.stem, type(exc).__name__, str(exc)))


def _junit_suite(suites: list, name: str, out_dir: Path, record) -> None:
    """Add the run's test suite (from its record, or the one its folder holds after a fault)."""
    from mobot_cli.record import junit
    from mobot_cli.record.summary import RunRecord

    record = record or RunRecord.load(out_dir)
    if record is not None:
        suites.append(junit.run_suite(record, name))


class _Watcher:
    """--view: the live page during the run, then a replay of the run folder until Ctrl-C."""

    def __init__(self, env, plan, port: int):
        from mobot_cli.view.live import LiveView
        from mobot_cli.view.page import open_page, url

        self.plan = plan  # the replay draws the world from it: the user's own, not read back confined
        self.env, self.server = env, open_page(port, label=f"mobot run: {plan.name}")
        self.url = url(self.server)
        self.live = LiveView(self.server, plan)
        output.view_live(env, self.url)

    def watch(self, timeline) -> None:
        self.live.watch(timeline)

    def replay(self, out_dir: Path) -> None:
        """Turn the page into a replay of the finished run and wait for Ctrl-C."""
        from mobot_cli.cli.view import wait_for_interrupt
        from mobot_cli.view.replay import Replay
        from mobot_cli.view.runfolder import read_run

        self.live.close()
        replay = None
        try:
            self.server.scene.reset()
            self.live.clock.content = "the run finished: replay it below"
            replay = Replay(self.server, [out_dir], read_run(out_dir, self.plan),
                            on_notice=lambda line: output.notices(self.env, [line]), robot_list=self.live.robot_list)
            output.view_held(self.env, self.url, out_dir)
            wait_for_interrupt()
        except KeyboardInterrupt:
            pass
        finally:
            if replay is not None:
                replay.close()
            self.close()

    def close(self) -> None:
        from mobot_cli.view.page import close_page

        self.live.close()
        close_page(self.server)


def _progress(bar, realtime: bool, rate_hz: int):
    """Advance the bar and, with --realtime, sleep so sim time never runs ahead of the clock."""
    if bar is None and not realtime:
        return None
    start = time.perf_counter()

    def update(step: int, total: int) -> None:
        if bar is not None:
            bar.update(bar.task_ids[0], completed=step)
        if realtime:
            ahead = step / rate_hz - (time.perf_counter() - start)
            if ahead > 0:
                time.sleep(ahead)

    return update
