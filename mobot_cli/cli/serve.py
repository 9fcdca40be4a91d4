"""`mobot serve [WORLD or SCENARIO]`: keep a headless world running and answer live requests."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from mobot_cli.cli import output, ros2
from mobot_cli.cli.live import common
from mobot_cli.errors import ExitCode, UsageError


def serve(
    ctx: typer.Context,
    target: Optional[str] = typer.Argument(None, metavar="[WORLD or SCENARIO]",
                                           help="A world (bundled name or file) or a scenario .yaml [default: empty]."),
    endpoint: common.Endpoint = None,
    bind_any: bool = typer.Option(False, "--bind-any", help="Allow a TCP endpoint that is not loopback."),
    realtime: bool = typer.Option(False, "--realtime", help="Step in real time (the default)."),
    fast: bool = typer.Option(False, "--fast", help="Step as fast as possible."),
    rtf: Optional[float] = typer.Option(None, "--rtf", metavar="X", help="Step at X times real time."),
    out: Optional[Path] = typer.Option(None, "--out", "-o", help="Record odometry, history and a summary here."),
    set_: list[str] = typer.Option([], "--set", help="Override a key, e.g. physics.rate_hz=480 (repeatable)."),
    duration: Optional[float] = typer.Option(None, "--duration", help="Stop after this many simulated seconds."),
    load_timeout: float = typer.Option(10.0, "--load-timeout", metavar="S",
                                       help="CPU seconds a spawned description may take to load "
                                            "(and 3x as long in wall time)."),
    load_memory: int = typer.Option(1024, "--load-memory", metavar="MIB",
                                    help="Memory limit of the process that loads spawned descriptions."),
    max_faces: int = typer.Option(100_000, "--max-faces", metavar="N",
                                  help="Mesh faces (collision and visual) a spawned robot may have."),
    max_links: int = typer.Option(200, "--max-links", metavar="N", help="Links a spawned robot may have."),
    max_robots: int = typer.Option(100, "--max-robots", metavar="N",
                                   help="Robots the world may hold; spawns beyond are refused."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="Print nothing but errors."),
    ros2_: bool = typer.Option(False, "--ros2", help=ros2.HELP),
    view: bool = typer.Option(False, "--view", help="Watch and drive the world in a local 3D web page "
                              "(extra 'view'): pause, resume, step, a teleop pad."),
    view_port: int = typer.Option(8080, "--view-port", help="Port of the --view page on 127.0.0.1 (0: any)."),
    view_max_steps: int = typer.Option(10_000, "--view-max-steps", metavar="N",
                                       help="Physics steps one Step click of the --view page may take."),
    paused: bool = typer.Option(False, "--paused", help="Start paused: the world moves only when asked to "
                                "(`mobot step`, `mobot resume`), for lockstep clients."),
) -> int:
    """Keep a headless world running; spawn, delete, drive and read robots with the other commands."""
    from mobot_cli.live.endpoint import default_endpoint, ipc_path
    from mobot_cli.live.keys import authorise_hint
    from mobot_cli.live.loader import Limits
    from mobot_cli.live.server import LiveServer, pace_text
    from mobot_cli.record.summary import Status
    from mobot_cli.scenario.prepare import prepare_target
    from mobot_cli.scenario.units import steps

    env = ctx.obj
    pace = _pace(realtime, fast, rtf)
    if duration is not None and not duration > 0:
        raise UsageError(f"--duration {duration:g} must be above zero")
    if not 0 < load_timeout <= 3600 or not 256 <= load_memory <= 1 << 20:
        raise UsageError("--load-timeout must be above 0 and at most 3600 s, --load-memory at least 256 MiB",
                         hint="The defaults are 10 s and 1024 MiB.")
    for option, value in (("--max-faces", max_faces), ("--max-links", max_links), ("--max-robots", max_robots),
                          ("--view-max-steps", view_max_steps)):
        if not 1 <= value <= 10**9:
            raise UsageError(f"{option} {value} must be at least 1 and at most 1000000000")
    if view:
        from mobot_cli.view.page import require_viser

        require_viser()
    prepared = prepare_target(target, set_)
    plan = prepared.plan
    output.notices(env, plan.notices, quiet=quiet)
    stop_after = steps(duration, plan.physics.rate_hz) if duration is not None else None
    bridges = ros2.bridges(plan, ros2_)
    page = _Page(env, plan, view_port, view_max_steps) if view else None
    server = LiveServer(plan, endpoint or default_endpoint(), rtf=pace, bind_any=bind_any,
                        out_dir=out, resolved_yaml=prepared.resolved_yaml, stop_after=stop_after,
                        attachments=bridges, watch=page.watch if page else None,
                        paused=paused, limits=Limits(seconds=load_timeout, memory=load_memory * 2**20,
                                                    faces=max_faces, links=max_links, robots=max_robots))
    if page:
        page.connect(server)
    started: list = []  # the simulation_interfaces services (rclpy), once the world listens

    def ready(where: str) -> None:
        started.extend(ros2.services(env, bridges, where, plan.physics.rate_hz, quiet))
        if not quiet:
            common.status(env, f"serving '{plan.name}' (world {plan.world.name}, {len(plan.robots)} robot(s)) "
                               f"at {where}, {pace_text(pace)}, {plan.physics.rate_hz} Hz"
                               f"{', paused' if paused else ''}. "
                               "Stop with Ctrl-C or `mobot stop`.")
            ros2.joined(env, bridges, quiet=False)
            if ipc_path(where) is None:
                common.status(env, authorise_hint())

    try:
        result = server.serve(ready)
    finally:
        ros2.close_services(started)
        ros2.report(env, bridges, quiet)
        if page:
            page.close()
    if not quiet:
        t = result.steps / plan.physics.rate_hz
        where = f"; record in {out}" if out is not None else ""
        common.status(env, f"stopped after {t:.3f} s simulated, {sum(result.requests.values())} "
                           f"request(s){where}")
    if result.status == Status.FAULT:
        common.status(env, f"error: {result.error}")
        return ExitCode.SIMULATION_FAULT
    return ExitCode.OK


def _pace(realtime: bool, fast: bool, rtf: Optional[float]) -> Optional[float]:
    """Real-time factor: 1.0 by default, None for --fast."""
    if sum((realtime, fast, rtf is not None)) > 1:
        raise UsageError("give only one of --realtime, --fast and --rtf")
    if rtf is not None and not 0 < rtf <= 1000:
        raise UsageError(f"--rtf {rtf:g} must be above 0 and at most 1000", hint="Use --fast for no pacing.")
    return None if fast else (rtf or 1.0)


class _Page:
    """--view: the live page, its World buttons on the server's own pause state, its pad sending `cmd`."""

    def __init__(self, env, plan, port: int, max_steps: int):
        from mobot_cli.view.live import LiveView
        from mobot_cli.view.page import open_page, url

        self.server = open_page(port, label=f"mobot serve: {plan.name}")
        self.plan, self.live_server, self.max_steps = plan, None, max_steps
        self.live = LiveView(self.server, plan)
        output.view_live(env, url(self.server))

    def watch(self, timeline) -> None:
        self.live.watch(timeline)

    def connect(self, server) -> None:
        """The live server whose pause state the World buttons press and whose endpoint the pad sends `cmd` to."""
        from mobot_cli.view.controls import GateControl, add_controls

        self.live_server = server
        state = add_controls(self.server, GateControl(server.control, self._cmd),
                             lambda: self.live.robot_list.selected, self.plan.physics.rate_hz, self.max_steps)

        def show_state() -> None:  # a `mobot pause` or `resume` from any client shows on the page
            text = "paused" if server.control.paused else "running"
            if state.content != text:
                state.content = text

        self.live.on_frame = show_state

    def _cmd(self, name: str, linear: float, angular: float, seconds: float) -> Optional[str]:
        from mobot_cli.errors import MobotError
        from mobot_cli.live.client import Client

        try:
            with Client(self.live_server.endpoint, timeout=2.0) as client:
                reply = client.cmd(name, linear, angular, for_=seconds)
        except MobotError as exc:
            return str(exc)
        return None if reply.get("ok") else f"{reply.get('result')}: {reply.get('message')}"

    def close(self) -> None:
        from mobot_cli.view.page import close_page

        self.live.close()
        close_page(self.server)
