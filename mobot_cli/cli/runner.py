"""What `mobot run` does once its command line is read: by Typer (run.py) or, for the plain
forms, by cli/fastpath.py, which keeps Typer out of a run's start-up."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Optional, Sequence

from mobot_cli.cli import output, ros2
from mobot_cli.cli.args import default_out
from mobot_cli.cli.environment import Environment
from mobot_cli.cli.startup import collect_garbage
from mobot_cli.errors import ExitCode
from mobot_cli.run.ahead import Ahead, take


def run_scenario(env: Environment, scenario: Path, out: Optional[Path] = None, set_: Sequence[str] = (),
                 seed: Optional[int] = None, duration: Optional[float] = None, realtime: bool = False,
                 json_: bool = False, quiet: bool = False, skip_missing: bool = False, ros2_: bool = False,
                 view: bool = False, view_port: int = 8080) -> int:
    """Run a scenario to its end, write the run folder and print what `mobot run` prints; the exit code."""
    overrides = list(set_)
    if seed is not None:
        overrides.append(f"seed={seed}")
    if duration is not None:
        overrides.append(f"duration={duration}")
    if skip_missing:
        overrides.append("skip_missing=true")
    if view:
        from mobot_cli.view.page import require_viser

        require_viser()  # before the run, not after it
    # The entry point's helper process validates and resolves the scenario this one reads, while
    # this one imports the engine.
    ahead = take()
    try:
        if ahead:
            from mobot_cli.scenario.overrides import read_ready

            ahead.prepare(read_ready(scenario, overrides))  # a bad file or --set: reported as prepare() does
        return _run(env, ahead, scenario, overrides, out, realtime, json_, quiet, ros2_, view, view_port)
    finally:
        if ahead:
            ahead.close()


def _run(env: Environment, ahead: Ahead | None, scenario: Path, overrides: list[str], out: Optional[Path],
         realtime: bool, json_: bool, quiet: bool, ros2_: bool, view: bool, view_port: int) -> int:
    from mobot_cli.common.files import check_out_folder
    from mobot_cli.run.execute import connect_ahead, execute, leave_at_exit

    if ahead:  # forked by the entry point, so this process ends with the run (not so under invoke())
        leave_at_exit()  # no disconnecting PyBullet first
        connect_ahead()  # while the helper still prepares the plan
    prepared = ahead.prepared() if ahead else None
    if prepared is None:  # no helper, or it could not: here, where its errors are reported
        from mobot_cli.run.prepare import prepare

        done = prepare(scenario, overrides)
        plan, resolved_yaml, painter = done.plan, done.resolved_yaml, None
    else:
        from mobot_cli.scenario.yamlsource import to_yaml

        (plan, document), painter = prepared, ahead
        resolved_yaml = to_yaml(document)
    collect_garbage()  # loaded: from here on garbage is made, and collected
    output.notices(env, plan.notices, quiet=quiet or json_)
    bridges = ros2.bridges(plan, ros2_)
    out_dir = out or default_out("runs", plan.name)
    check_out_folder(out_dir)  # a file, a path under a file, a read-only folder: before the run
    bar = None if (quiet or json_) else output.progress_bar(env, plan.total_steps, plan.name)
    progress = _progress(bar, realtime, plan.physics.rate_hz)
    ros2.joined(env, bridges, quiet=quiet or json_)
    watcher = _Watcher(env, plan, view_port) if view else None
    if bar:
        bar.start()
    try:
        result = execute(plan, resolved_yaml, out_dir, progress=progress, attachments=bridges,
                         watch=watcher.watch if watcher else None, painter=painter)
    except BaseException:
        if watcher:
            watcher.close()
        raise
    finally:
        if bar:
            bar.stop()
        ros2.report(env, bridges, quiet=quiet or json_)
    if ahead:
        ahead.close()  # the picture is drawn: nothing is left for it to do
    if json_:
        output.emit_json(env, result.record.to_dict())
    elif not quiet:
        output.run_table(env, result.record, result.out_dir)
    output.expectations(env, result.expectations, verbose=not (quiet or json_))
    if watcher:
        watcher.replay(result.out_dir)
    if any(not r.passed for r in result.expectations):
        return ExitCode.EXPECTATION_FAILED
    return ExitCode.OK


class _Watcher:
    """--view: the live page during the run, then a replay of the run folder until Ctrl-C."""

    def __init__(self, env, plan, port: int):
        from mobot_cli.view.live import LiveView
        from mobot_cli.view.page import open_page, url

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
            replay = Replay(self.server, [out_dir], read_run(out_dir),
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
