"""`mobot view RUN_DIR [--port N]`: replay a run folder (or a sweep's runs) in a local 3D web page."""

from __future__ import annotations

from pathlib import Path

import typer

from mobot_cli.cli import output
from mobot_cli.errors import ExitCode

PORT = typer.Option(8080, "--port", help="Port of the page on 127.0.0.1 (the next free one if taken; 0: any).")


def view(
    ctx: typer.Context,
    folder: Path = typer.Argument(..., help="A run folder, or a sweep folder (pick a run in the page)."),
    port: int = PORT,
) -> int:
    """Open a 3D view of a run in the browser: world, robots, paths, readings, a timeline."""
    from mobot_cli.view.page import close_page, open_page, require_viser, url
    from mobot_cli.view.replay import Replay
    from mobot_cli.view.runfolder import read_run, runs_of

    env = ctx.obj
    require_viser()
    runs = runs_of(folder)
    first = read_run(runs[0])  # refuse a folder with nothing to show before a page opens
    server = open_page(port, label=f"mobot view: {folder.name}")
    replay = None
    try:
        replay = Replay(server, runs, first, on_notice=lambda line: output.notices(env, [line]))
        output.view_ready(env, url(server), f"{len(runs)} runs of {folder}" if len(runs) > 1 else str(folder))
        wait_for_interrupt()
    except KeyboardInterrupt:
        pass
    finally:
        if replay is not None:
            replay.close()
        close_page(server)
    return ExitCode.OK


def wait_for_interrupt() -> None:
    """Sleep until Ctrl-C or SIGTERM (the page is served by viser's own thread meanwhile)."""
    import signal
    import threading

    if threading.current_thread() is threading.main_thread():
        old = signal.signal(signal.SIGTERM, _interrupt)
        try:
            threading.Event().wait()
        finally:
            signal.signal(signal.SIGTERM, old)
    else:
        threading.Event().wait()


def _interrupt(signum, frame) -> None:
    raise KeyboardInterrupt
