"""The garbage collector during start-up: held back by the entry point, started by the CLI.

A `mobot run` makes ~45k objects that the collector tracks while it starts (modules, classes,
the plan) and little garbage, yet the collector would scan them all several times over.
__main__.entry() disables it; the CLI starts it again once a command has loaded what it needs.
"""

from __future__ import annotations

import gc


def collect_garbage() -> None:
    """Start the garbage collector if the entry point held it back (__main__.py), the objects made
    until now frozen: they live as long as the process, and later collections skip them."""
    if not gc.isenabled():
        gc.freeze()
        gc.enable()
