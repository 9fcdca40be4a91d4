"""Only the page's owner reaches the view, as Jupyter does it: a token, the Host and the Origin.

The page listens on 127.0.0.1, which every local user and every web page in the owner's browser
can reach (a page of another site gets there by DNS rebinding: its name resolves to 127.0.0.1,
so the browser calls it same-origin). So every HTTP request and the websocket handshake must show
- the token: ``?token=`` in the URL printed to the owner only, or the cookie the page gets with it
  (viser's page opens its websocket without the query, the browser sends the cookie along);
- a Host of 127.0.0.1, localhost or [::1] at the page's port (a rebinding page sends its own name);
- no Origin, or the page's own (a browser always sends one on a websocket, a foreign page's is its own).
Anything else gets 403 before viser reads a byte of it, so no scene data leaves.

viser has no hook for its handshake; it passes its own ``process_request`` to
``websockets.asyncio.server.serve`` while the server starts. ``guarded`` wraps that one call
(viser's module sees a websockets whose ``serve`` adds the guard, only while it is constructed),
and ``page.open_page`` refuses to serve when the wrap did not take (a viser laid out differently).
"""

from __future__ import annotations

import contextlib
import http
import secrets
import threading
from typing import Any, Callable, Iterator
from urllib.parse import parse_qs, urlsplit

LOOPBACK_NAMES = ("127.0.0.1", "localhost", "[::1]")
_SWAP = threading.Lock()  # one viser module global is swapped at a time


class Guard:
    """The token and the checks for one page."""

    def __init__(self) -> None:
        self.token = secrets.token_urlsafe(32)
        self.installed = False  # set when viser's server took the wrapped process_request
        self.refused = 0

    def cookie_name(self, port: int) -> str:
        # Cookies are shared across ports of one host: one name per page keeps two views apart.
        return f"mobot-view-{port}"

    def why_refused(self, request: Any, port: int) -> str | None:
        """Why ``request`` (a websockets Request) may not reach the page, or None."""
        hosts, origins = request.headers.get_all("Host"), request.headers.get_all("Origin")
        if len(hosts) != 1 or hosts[0] not in {f"{name}:{port}" for name in LOOPBACK_NAMES}:
            return "wrong Host (the view answers only 127.0.0.1, localhost or [::1] at its port)"
        if len(origins) > 1 or origins and origins[0] != f"http://{hosts[0]}":
            return "foreign Origin (only the page itself may open its websocket)"
        if not self._has_token(request, port):
            return "no valid token (open the address mobot printed, with its ?token=)"
        return None

    def _has_token(self, request: Any, port: int) -> bool:
        given = parse_qs(urlsplit(request.path).query).get("token", [])
        for header in request.headers.get_all("Cookie"):
            for part in header.split(";"):
                name, _, value = part.strip().partition("=")
                if name == self.cookie_name(port):
                    given.append(value)
        return any(secrets.compare_digest(value.encode(), self.token.encode()) for value in given)

    def wrap(self, process_request: Callable | None) -> Callable:
        """viser's ``process_request`` behind the checks; the page's reply sets the token's cookie."""

        def process(connection: Any, request: Any) -> Any:
            port = connection.local_address[1]
            why = self.why_refused(request, port)
            if why is not None:
                self.refused += 1
                return connection.respond(http.HTTPStatus.FORBIDDEN, f"mobot view: {why}\n")
            response = process_request(connection, request) if process_request is not None else None
            if response is not None and "token=" in request.path:
                response.headers["Set-Cookie"] = (f"{self.cookie_name(port)}={self.token}; Path=/; "
                                                  "HttpOnly; SameSite=Strict")
            return response

        self.installed = True
        return process


class _Overlay:
    """A module seen through a few replaced attributes."""

    def __init__(self, module: Any, **replaced: Any):
        self._module, self._replaced = module, replaced

    def __getattr__(self, name: str) -> Any:
        return self._replaced[name] if name in self._replaced else getattr(self._module, name)


@contextlib.contextmanager
def guarded(guard: Guard) -> Iterator[None]:
    """While viser starts its server inside this block, that server checks every request with ``guard``."""
    from viser.infra import _infra

    real = getattr(_infra, "websockets", None)
    if real is None:  # a viser laid out differently: open_page refuses, guard.installed stays False
        yield
        return

    def serve(*args: Any, process_request: Callable | None = None, **kwargs: Any) -> Any:
        return real.asyncio.server.serve(*args, process_request=guard.wrap(process_request), **kwargs)

    with _SWAP:
        _infra.websockets = _Overlay(real, asyncio=_Overlay(real.asyncio, server=_Overlay(real.asyncio.server,
                                                                                          serve=serve)))
        try:
            yield
        finally:
            _infra.websockets = real
