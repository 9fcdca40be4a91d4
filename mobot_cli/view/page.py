"""The viser server behind every view: local, quiet, offline, with the scene set up for robots.

viser prints a banner and "Server stopped" on the process's stdout; only the CLI prints in
mobot, so both are swallowed here and the CLI prints the URL itself. The page's "share" button
would open a public tunnel through viser's relay: it is hidden and its handler disabled, so
nothing leaves the machine. Every request must come from the owner (guard.py): the address
carries a random token, and Host and Origin are checked.
"""

from __future__ import annotations

import contextlib
import io
from typing import Any

from mobot_cli.errors import UsageError

HOST = "127.0.0.1"
DEFAULT_PORT = 8080
INSTALL_HINT = ("Install the view extra: pip install 'mobot-cli[view]' (it brings viser, whose web page "
                "ships inside the wheel and works offline).")


class ViewUnavailable(UsageError):
    """The optional `view` extra (viser) is not installed."""


def require_viser() -> Any:
    """The viser module, or ViewUnavailable (exit 2) saying how to install it."""
    try:
        import viser
    except ImportError:
        raise ViewUnavailable("the 3D view needs viser, which is not installed", hint=INSTALL_HINT) from None
    return viser


def open_page(port: int = DEFAULT_PORT, label: str = "mobot") -> Any:
    """A running ViserServer on 127.0.0.1:``port`` (the next free port if taken; 0: any)."""
    viser = require_viser()
    if not 0 <= port <= 65535:
        raise UsageError(f"--port {port} is not a TCP port (0-65535)")
    from mobot_cli.view.guard import Guard, guarded

    guard = Guard()
    with contextlib.redirect_stdout(io.StringIO()), guarded(guard):
        server = viser.ViserServer(host=HOST, port=port, label=label, verbose=False)
    if not guard.installed:  # never serve a page anyone on the machine could drive
        close_page(server)
        raise ViewUnavailable(f"viser {getattr(viser, '__version__', '?')} starts its server in a way mobot "
                              "cannot guard with a token", hint="Install viser 1.x (pip install 'viser>=1.0,<2').")
    server.mobot_guard = guard
    server.request_share_url = lambda *args, **kwargs: None  # never tunnel out (see above)
    server.gui.configure_theme(show_share_button=False, control_width="large", brand_color=(38, 89, 191))
    server.scene.set_up_direction("+z")  # ROS: z up
    server.scene.world_axes.visible = False
    return server


def url(server: Any) -> str:
    """The page's address, with the token only its owner gets (print it to the owner alone)."""
    return f"http://{HOST}:{server.get_port()}/?token={server.mobot_guard.token}"


def close_page(server: Any) -> None:
    """Stop the server without its goodbye line on stdout."""
    with contextlib.redirect_stdout(io.StringIO()):
        server.stop()
        # stop() waits a second at most; the goodbye line comes when the thread ends.
        thread = getattr(getattr(server, "_websock_server", None), "_server_thread", None)
        if thread is not None:
            thread.join(timeout=5.0)
