"""All terminal output of mobot: errors, notices, tables and progress. Rich lives only here.

Every function writes to the streams of the Environment it is given, never to sys.stdout.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Iterable

from mobot_cli.cli.environment import Environment
from mobot_cli.errors import MobotError


def report_error(env: Environment, exc: MobotError) -> None:
    """One short paragraph on stderr, no traceback."""
    env.stderr.write(f"mobot: error: {exc}\n")


def notices(env: Environment, lines: Iterable[str], quiet: bool = False) -> None:
    """Print warnings that did not stop the command."""
    if quiet:
        return
    for line in lines:
        env.stderr.write(f"mobot: warning: {line}\n")


def emit_json(env: Environment, data: Any, one_line: bool = False) -> None:
    """Print a JSON document on stdout, for scripts; ``one_line``: compact, one line (JSON Lines)."""
    import json  # --json only

    env.stdout.write((json.dumps(data) if one_line else json.dumps(data, indent=2)) + "\n")


def stdout_console(env: Environment):
    """A Rich console on stdout (imported lazily: Rich is not needed for --help or --json)."""
    return _console(env, stderr=False, highlight=False, soft_wrap=True)  # never hard-wrap lines scripts grep


def _console(env: Environment, stderr: bool, **options: Any):
    """A Rich console on env's stdout or stderr, styled and sized as env decided."""
    from rich.console import Console

    stream, tty = (env.stderr, env.stderr_isatty) if stderr else (env.stdout, env.stdout_isatty)
    options.setdefault("width", env.width)
    if env.color is None:
        # A terminal we know of, or else Rich's own look (FORCE_COLOR, the stream's isatty()).
        return Console(file=stream, force_terminal=True if tty else None, **options)
    return Console(file=stream, force_terminal=tty or env.color, no_color=not env.color, **options)


def progress_bar(env: Environment, total: int, label: str):
    """A Rich progress bar on stderr when it is a terminal; otherwise None."""
    if not env.stderr_isatty:
        return None
    from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

    bar = Progress(TextColumn("{task.description}"), BarColumn(), TextColumn("{task.percentage:>3.0f}%"),
                   TimeRemainingColumn(), console=_console(env, stderr=True), transient=True)
    bar.add_task(label, total=total)
    return bar


def run_table(env: Environment, record, out_dir) -> None:
    """The per-robot table printed after a run (``record`` is a RunRecord)."""
    from rich.table import Table

    table = Table(title=f"{record.scenario}: {record.sim_time:g} s simulated in "
                        f"{record.wall_time:g} s ({record.real_time_factor}x real time)",
                  caption="final pose x, y (m), yaw (rad); distance and odometry error in m")
    # Short headers: the table must fit 80 columns (pipes and CI logs) without wrapping.
    for column in ("robot", "distance", "x", "y", "yaw", "odom error", "collisions"):
        table.add_column(column, justify="left" if column == "robot" else "right")
    for name, robot in record.robots.items():
        pose = robot.final_pose
        table.add_row(name, f"{robot.distance:.3f}", f"{pose.x:.3f}", f"{pose.y:.3f}",
                      f"{pose.yaw:.3f}", f"{robot.odom_error.position:.3f}", str(robot.collisions))
    console = stdout_console(env)
    console.print(table)
    goals = [(name, goal) for name, robot in record.robots.items() for goal in robot.goals]
    if goals:
        console.print(_goal_table(goals))
        for name, goal in goals:  # why a planned goal could not start, under the table
            if goal.reason:
                which = f"goal {goal.command}" if goal.command is not None else "live goal"
                console.print(f"{name} {which} {goal.status}: {goal.reason}")
    written = [name for name in ("trajectory.png", "bag/") if (Path(out_dir) / name.rstrip("/")).exists()]
    console.print(f"run folder: {out_dir}" + (f" ({', '.join(written)})" if written else ""))


def _goal_table(goals: list) -> Any:
    """One row per goal command: how it ended, how long it took, how far the robot drove."""
    from rich.table import Table

    table = Table(title="goals", caption="time in s; path driven, final distance from the goal and least "
                                         "clearance in m; hits: collisions; (why it failed): docs/metrics.md")
    for column in ("robot", "command", "status", "time", "path", "error", "spl", "clear", "hits"):
        table.add_column(column, justify="left" if column in ("robot", "command", "status") else "right",
                         overflow="fold")
    for name, goal in goals:
        which = f"{goal.command} {goal.kind}" if goal.command is not None else f"live {goal.kind}"
        laps = f" ({goal.laps} lap{'s' if goal.laps != 1 else ''})" if goal.laps is not None else ""
        table.add_row(name, which, _status(goal) + laps, f"{goal.time:.2f}", f"{goal.path_length:.2f}",
                      _maybe(goal.error, 3), _maybe(goal.spl, 2), _maybe(goal.clearance_min, 3),
                      "-" if goal.collisions is None else str(goal.collisions))
    return table


def _status(goal) -> str:
    """A goal's status, and its metrics' failure where that says more (blocked (collision))."""
    said = {"timed_out": "timeout", "unreachable": "unreachable", "stuck": "stuck"}.get(goal.status)
    if not goal.failure or goal.failure == said:
        return goal.status
    return f"{goal.status} ({goal.failure})"


def _maybe(value, digits: int) -> str:
    return "-" if value is None else f"{value:.{digits}f}"


def check_result(env: Environment, result: dict[str, Any]) -> None:
    """One line saying what was checked and that it is fine."""
    if result["kind"] == "world":
        world_summary(env, result)
        return
    if result["kind"] == "scenario":
        line = (f"ok: scenario '{result['name']}': {len(result['robots'])} robot(s), "
                f"{result['duration']:g} s ({result['steps']} steps)")
    else:
        line = f"ok: robot '{result.get('name', result['path'])}' ({result['path']})"
    env.stdout.write(line + "\n")


_TREE_WIDTH = 100_000  # columns: wide enough that no tree line is cut


def inspect_tree(env: Environment, summary: dict[str, Any]) -> None:
    """The link/joint tree, mass, footprint and drive of a robot, as a Rich tree."""
    from rich.tree import Tree

    def add(branch, node: dict[str, Any]) -> None:
        for child in node["children"]:
            label = f"{child['link']}  [dim]({child['type']} joint {child['joint']}, {child['mass']:g} kg)[/]"
            add(branch.add(label), child)

    root = summary["tree"]
    tree = Tree(f"[bold]{root['link']}[/]  [dim]({root['mass']:g} kg)[/]")
    add(tree, root)
    console = stdout_console(env)
    console.print(f"[bold]{summary['name']}[/]  {summary['source']}")
    # A terminal wraps long labels; a pipe or file gets whole lines (Rich would crop them).
    wide = console if env.stdout_isatty else _console(env, stderr=False, highlight=False,
                                                      soft_wrap=True, width=_TREE_WIDTH)
    wide.print(tree)
    fp = summary["footprint"]
    console.print(f"total mass {summary['total_mass']:.3f} kg; footprint {fp['length']:.3f} x {fp['width']:.3f} m "
                  f"(x {fp['xmin']:.3f}..{fp['xmax']:.3f}, y {fp['ymin']:.3f}..{fp['ymax']:.3f}, "
                  f"z {summary['bottom_z']:.3f}..{summary['top_z']:.3f})")
    drive = summary["drive"]
    if drive is None and summary.get("refused_drive"):
        console.print(f"drive: mobot cannot drive its {summary['refused_drive']}: a passive body")
    elif drive is None:
        console.print("drive: none detected (set drive: in the scenario to command this robot)")
    elif drive.get("kind") == "ackermann":
        console.print(f"drive ({drive['source']}): ackermann; steering {', '.join(drive['steering_joints'])}; "
                      f"driven {', '.join(drive['left_joints'] + drive['right_joints'])}; wheel radius "
                      f"{drive['wheel_radius']:.4f} m, track {drive['wheel_separation']:.4f} m, wheelbase "
                      f"{drive['wheelbase']:.4f} m; max steering {drive['max_steering_angle']:.4f} rad, "
                      f"min turning radius {drive['min_turning_radius']:.3f} m; odometry {drive['odometry']}")
    elif drive.get("kind") in ("mecanum", "omni") and not (drive["left_joints"] or drive["right_joints"]):
        console.print(f"{drive['kind']} drive ({drive['source']}, holonomic: takes linear_y): no wheel joints, the "
                      f"body is moved as gazebo_ros's planar_move moves it; odometry {drive['odometry']}")
    elif drive.get("kind") in ("mecanum", "omni"):
        left, right = ", ".join(drive["left_joints"]) or "none", ", ".join(drive["right_joints"]) or "none"
        console.print(f"{drive['kind']} drive ({drive['source']}, holonomic: takes linear_y): "
                      f"left {left}; right {right}; "
                      f"wheel radius {drive['wheel_radius']:.4f} m, separation {drive['wheel_separation']:.4f} m, "
                      f"wheelbase {drive['wheelbase']:.4f} m; odometry {drive['odometry']}")
    else:
        console.print(f"drive ({drive['source']}): left {', '.join(drive['left_joints'])}; right "
                      f"{', '.join(drive['right_joints'])}; wheel radius {drive['wheel_radius']:.4f} m, "
                      f"separation {drive['wheel_separation']:.4f} m x {drive['wheel_separation_multiplier']:g}; "
                      f"max torque {drive['max_wheel_torque']:g} N*m")
    console.print("sensors:" if summary["sensors"] else "sensors: none")
    for sensor in summary["sensors"]:
        for line in sensor_lines(sensor):
            console.print(line, markup=False)


def sensor_lines(s: dict[str, Any]) -> list[str]:
    """Two short lines per sensor (they fit 80 columns): where and how often, then what it measures."""
    rate = f"{s['rate_hz']:g} Hz" if s["rate_hz"] else "every step"
    kind = s["kind"]
    if kind == "lidar":
        kind = "3D lidar" if s["vertical_samples"] > 1 else "2D lidar"
    what = s["type"] if s["type"] == kind else f"{s['type']}, {kind}"
    head = f"  {s['name']} ({what}) on {s['link']}, topic {s['topic']}, {rate}"
    if s["kind"] == "lidar":
        rays = f"{s['samples']}" + (f" x {s['vertical_samples']}" if s["vertical_samples"] > 1 else "")
        detail = (f"{rays} ray{'s' if rays != '1' else ''} {s['min_angle']:.3f}..{s['max_angle']:.3f} rad, range "
                  f"{s['range_min']:g}..{s['range_max']:g} m, noise {s['noise_stddev']:g} m")
    elif s["kind"] == "range":
        rays = s["samples"] * s["vertical_samples"]
        detail = (f"{s['radiation']}, {rays} ray{'s' if rays != 1 else ''}, field of view "
                  f"{s['field_of_view']:.3f} rad, range {s['range_min']:g}..{s['range_max']:g} m, "
                  f"noise {s['noise_stddev']:g} + {s['reading_noise_stddev']:g} m")
    elif s["kind"] == "imu":
        detail = f"noise: gyro {s['noise_stddev']:g} rad/s, accel {s['accel_noise_stddev']:g} m/s^2"
    elif s["kind"] in ("camera", "depth", "rgbd"):
        what = {"camera": "RGB", "depth": "depth", "rgbd": "RGB-D"}[s["kind"]]
        detail = (f"{what} {s['width']} x {s['height']} {s['image_format']}, field of view "
                  f"{s['horizontal_fov']:.3f} rad, clip {s['clip_near']:g}..{s['clip_far']:g} m, "
                  f"noise {s['noise_stddev']:g}")
    else:
        detail = f"contacts of {s['collision'] or 'the whole link'}"
    frame = f", frame {s['frame_id']}" if s["frame_id"] != s["link"] else ""
    return [head + frame, f"    {detail}"]


def expectations(env: Environment, results, verbose: bool = True) -> None:
    """Each expectation and how it went; when quiet, the failures alone on stderr, for scripts."""
    failed = [r for r in results if not r.passed]
    if verbose and results:
        console = stdout_console(env)
        for r in results:
            mark = "[green]pass[/]" if r.passed else "[bold red]FAIL[/]"
            console.print(f"{mark}  {r.robot}: expected to {r.expected}; it {r.happened}", markup=True,
                          highlight=False)
        if failed:
            env.stderr.write(f"mobot: {len(failed)} of {len(results)} expectations failed\n")
        return
    for r in failed:
        env.stderr.write(f"mobot: expectation failed: robot '{r.robot}' was expected to {r.expected}; "
                         f"it {r.happened}\n")


def sweep_progress(env: Environment, total: int, label: str):
    """A Rich bar for a sweep (runs done, failed, ETA) on stderr when it is a terminal; else None."""
    if not env.stderr_isatty:
        return None
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    bar = Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                   TextColumn("runs, [red]{task.fields[failed]} failed[/]"), TimeElapsedColumn(),
                   TextColumn("ETA"), TimeRemainingColumn(), console=_console(env, stderr=True), transient=True)
    bar.add_task(label, total=total, failed=0)
    return bar


def sweep_updates(bar):
    """What a sweep calls as runs end (done, failed, total): the bar moves; None without a bar."""
    if bar is None:
        return None

    def update(done: int, failed: int, total: int) -> None:
        bar.update(bar.task_ids[0], completed=done, failed=failed)

    return update


def sweep_summary(env: Environment, out_dir, rows: list[dict[str, str]], keys: list[str], total: int, skipped: int,
                  wall: float, goals: dict[str, Any] | None = None) -> None:
    """The failed runs (if any) as a table, then one line of counts and where the results are."""
    from rich.markup import escape
    from rich.table import Table

    console = stdout_console(env)
    failed = [r for r in rows if r["status"] == "failed"]
    if failed:
        table = Table(title=f"{len(failed)} failed run{'s' if len(failed) != 1 else ''}")
        for column in ("run", "values", "failure", "reason"):
            table.add_column(column, overflow="fold")
        short = _short_keys(keys)
        for r in failed[:50]:
            values = ", ".join(f"{short[k]}={r[k]}" for k in keys)
            table.add_row(r["run"], escape(values), r["failure"], escape(r["reason"]))
        console.print(table)
        if len(failed) > 50:
            console.print(f"... and {len(failed) - 50} more in results.csv")
    resumed = f" ({skipped} from before --resume)" if skipped else ""
    console.print(f"{len(rows)} of {total} runs done{resumed}: {len(rows) - len(failed)} passed, "
                  f"{len(failed)} failed, in {wall:.1f} s", highlight=False)
    for name, g in (goals or {}).items():  # robots with goals: their success rate over the runs
        if g["runs"]:
            console.print(f"{name}: goals reached in {g['successes']} of {g['runs']} runs (success rate "
                          f"{g['success_rate']:.2f}), mean SPL {g['mean_spl']:.3f}"
                          + (f", mean time {g['mean_time']:.2f} s" if g["mean_time"] is not None else ""),
                          highlight=False)
    console.print(f"results: {out_dir}/results.csv", highlight=False)


def sweep_failures(env: Environment, out_dir, failed: int, total: int) -> None:
    """When quiet: one line on stderr if any run failed."""
    if failed:
        env.stderr.write(f"mobot: {failed} of {total} runs failed; see {out_dir}/results.csv\n")


def sweep_interrupted(env: Environment, out_dir) -> None:
    """Where the finished rows are and how to go on."""
    env.stderr.write(f"mobot: sweep stopped; finished runs are in {out_dir}/results.csv. "
                     f"Go on with: --resume --out {out_dir}\n")


def world_summary(env: Environment, result: dict[str, Any]) -> None:
    """What `mobot check WORLD` found: models, shapes, meshes, robots, what it ignored, extent."""
    def plural(n: int, word: str) -> str:
        return f"{n} {word}{'' if n == 1 else 's'}"

    shapes = result["shapes"]
    meshes = result["meshes"]
    lines = [f"ok: world '{result['name']}' ({result['path']})",
             f"  models   {result['models']} ({result['static_models']} static"
             + (f", {result['held_fixed']} of them held fixed" if result["held_fixed"] else "")
             + (f", {len(result['skipped_models'])} left out" if result["skipped_models"] else "") + ")",
             f"  shapes   {plural(sum(shapes.values()), 'collision shape')} in {plural(result['links'], 'link')}"
             + (": " + ", ".join(f"{k} {v}" for k, v in shapes.items()) if shapes else ""),
             "  meshes   " + (f"{plural(meshes['files'], 'file')}, {plural(meshes['triangles'], 'triangle')}; "
                              f"{meshes['converted']} COLLADA converted to OBJ (cached)"
                              if meshes["files"] else "none"),
             "  ground   " + ("a ground plane at z = 0" if result["ground_plane"]
                              else "no ground plane: floors are world geometry")]
    robots = result["robots"]
    lines.append("  robots   " + (", ".join(robots) + " (list a name under robots: to drive it)"
                                  if robots else "none"))
    ignored = {k: v for k, v in result["ignored"].items() if v}
    if ignored:
        lines.append("  ignored  " + ", ".join(f"{k} x{v}" if v > 1 else k for k, v in ignored.items()))
    bounds = result["bounds"]
    if bounds:
        (x0, y0, z0), (x1, y1, z1), size = bounds["min"], bounds["max"], bounds["size"]
        lines.append(f"  extent   x {x0:.2f}..{x1:.2f}, y {y0:.2f}..{y1:.2f}, z {z0:.2f}..{z1:.2f} m "
                     f"({size[0]:.2f} x {size[1]:.2f} x {size[2]:.2f} m)")
    env.stdout.write("\n".join(lines) + "\n")


def _short_keys(keys: list[str]) -> dict[str, str]:
    """'robots.mobot.commands.0.linear' -> 'linear', or more of the key where that is ambiguous."""
    for n in range(1, max((k.count(".") + 1 for k in keys), default=1) + 1):
        short = {k: ".".join(k.split(".")[-n:]) for k in keys}
        if len(set(short.values())) == len(keys):
            return short
    return {k: k for k in keys}


def run_folder_status(env: Environment, result: dict[str, Any]) -> None:
    """How a run ended (mobot check RUN_DIR): a verdict line, then what the files hold."""
    what = f"run '{result['scenario']}'" if result.get("scenario") else "run"
    line = f"{result['status']}: {what} in {result['path']}"
    if result["status"] == "ok":
        line += f": {result['sim_time']:g} s simulated, {len(result['robots'])} robot(s), every file in place"
    elif result["problems"]:
        line += ": " + "; ".join(result["problems"])
    lines = [line]
    repaired = result.get("repaired")
    if repaired is not None:
        lines.insert(0, f"repaired {repaired['file']}: {repaired['messages']} messages from {repaired['chunks']} "
                        f"complete chunks, up to t = {repaired['last_t']:g} s; metadata.yaml written"
                     if repaired["done"] else f"nothing repaired: {repaired['why']}")
    if not result["ok"]:
        for robot, extent in result["csv"].items():
            upto = f", up to t = {extent['last_t']:g} s" if extent["last_t"] is not None else ""
            lines.append(f"  odom/{robot}.csv: {extent['rows']} whole rows{upto}")
        bag = result["bag"]
        if bag is not None and bag.get("file"):
            upto = f", messages up to t = {bag['last_t']:g} s" if bag.get("last_t") is not None else ""
            closed = "closed" if bag["complete"] else "not closed (no metadata.yaml)"
            lines.append(f"  bag/{bag['file']}: {closed}; {bag['chunks']} complete chunks{upto}")
            if bag.get("repairable"):
                lines.append(f"  bag can be repaired: mobot check {result['path']} --repair")
        for name, extent in result.get("sensors", {}).items():
            upto = f", up to t = {extent['last_t']:g} s" if extent["last_t"] is not None else ""
            lines.append(f"  {name}: {extent['rows']} whole rows{upto}")
    env.stdout.write("\n".join(lines) + "\n")


def plot_written(env: Environment, result) -> None:
    """Where mobot plot wrote its picture."""
    runs = f" from {result.runs} runs" if result.runs > 1 else ""
    env.stdout.write(f"wrote {result.out} ({result.tracks} path{'s' if result.tracks != 1 else ''}{runs})\n")


def view_ready(env: Environment, url: str, what: str) -> None:
    """`mobot view`: the page's address on stdout (the command's one result), at once."""
    env.stdout.write(f"view of {what}: {url}\n")
    env.stdout.flush()
    env.stderr.write("mobot: open the address in a browser; stop with Ctrl-C\n")
    env.stderr.flush()


def view_live(env: Environment, url: str) -> None:
    """`run --view` and `serve --view`: the page's address on stderr (stdout stays for data)."""
    env.stderr.write(f"mobot: live view at {url}\n")
    env.stderr.flush()


def view_held(env: Environment, url: str, out_dir) -> None:
    """After `run --view`: the page stays until Ctrl-C."""
    env.stderr.write(f"mobot: run finished; the view stays at {url} until Ctrl-C "
                     f"(replay it later with: mobot view {out_dir})\n")
    env.stderr.flush()
