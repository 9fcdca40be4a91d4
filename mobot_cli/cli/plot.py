"""`mobot plot RUN_DIR [--out FILE]`: redraw a run's trajectory.png, or overlay a sweep's runs."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from mobot_cli.cli import output
from mobot_cli.errors import ExitCode


def plot(
    ctx: typer.Context,
    folder: Path = typer.Argument(..., help="A run folder, or a sweep folder (every run overlaid)."),
    out: Optional[Path] = typer.Option(None, "--out", "-o", help="The PNG to write [default: FOLDER/trajectory.png]."),
) -> int:
    """Draw every robot's true path and odometry over the world's floor plan, as a PNG."""
    from mobot_cli.record.replot import replot

    result = replot(folder, out)
    output.notices(ctx.obj, result.notices)
    output.plot_written(ctx.obj, result)
    return ExitCode.OK
