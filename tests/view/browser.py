"""A real headless Chromium for tests, driven through its DevTools protocol (no browser download).

Debian's `chromium` (/usr/bin/chromium; .ci/run installs it) renders WebGL in software with
SwiftShader. The page is opened at a fixed size, its console errors and uncaught exceptions are
collected, and screenshots come back as RGB arrays (Pillow).
"""

from __future__ import annotations

import base64
import io
import itertools
import json
import shutil
import subprocess
import tempfile
import time
import urllib.request
from pathlib import Path

CHROMIUM = "/usr/bin/chromium"
FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--use-angle=swiftshader", "--enable-unsafe-swiftshader",  # WebGL without a GPU
         "--remote-debugging-port=0", "--remote-allow-origins=*", "--hide-scrollbars", "--mute-audio")


def available() -> str | None:
    """None when Chromium and a websocket client are here, else why not."""
    if not Path(CHROMIUM).is_file():
        return f"{CHROMIUM} is missing (Debian's chromium package; .ci/run installs it)"
    try:
        import websockets.sync.client  # noqa: F401 - comes with viser
    except ImportError:
        return "the websockets package is missing (it comes with the view extra)"
    return None


class Browser:
    """One headless Chromium with one page; use as a context manager."""

    def __init__(self, width: int = 1000, height: int = 700):
        self.width, self.height = width, height
        self.profile = Path(tempfile.mkdtemp(prefix="mobot-chromium-"))
        self.log = open(self.profile / "chromium.log", "w+")
        self.process = subprocess.Popen([CHROMIUM, *FLAGS, f"--user-data-dir={self.profile}",
                                         f"--window-size={width},{height}", "about:blank"],
                                        stdout=self.log, stderr=subprocess.STDOUT)
        self.errors: list[str] = []
        self._ids = itertools.count(1)
        self._socket = self._connect()
        for method in ("Page.enable", "Runtime.enable", "Log.enable"):
            self.call(method)
        self.call("Emulation.setDeviceMetricsOverride", width=width, height=height, deviceScaleFactor=1,
                  mobile=False)

    def __enter__(self) -> "Browser":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _connect(self):
        from websockets.sync.client import connect

        port_file = self.profile / "DevToolsActivePort"
        deadline = time.monotonic() + 30
        while not port_file.is_file() or not port_file.read_text().strip():
            if time.monotonic() > deadline or self.process.poll() is not None:
                raise RuntimeError(f"chromium did not start: {self._log_text()}")
            time.sleep(0.1)
        port = int(port_file.read_text().split()[0])
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=10) as reply:
            page = next(t for t in json.load(reply) if t["type"] == "page")
        return connect(page["webSocketDebuggerUrl"], max_size=None, open_timeout=10)

    def call(self, method: str, timeout: float = 30.0, **params):
        """Send one DevTools command and return its result (events meanwhile are collected)."""
        ident = next(self._ids)
        self._socket.send(json.dumps({"id": ident, "method": method, "params": params}))
        deadline = time.monotonic() + timeout
        while True:
            message = json.loads(self._socket.recv(timeout=max(0.1, deadline - time.monotonic())))
            if message.get("id") == ident:
                if "error" in message:
                    raise RuntimeError(f"{method}: {message['error']}")
                return message.get("result", {})
            self._event(message)

    def _event(self, message: dict) -> None:
        method, params = message.get("method"), message.get("params", {})
        if method == "Runtime.exceptionThrown":
            details = params.get("exceptionDetails", {})
            self.errors.append("exception: " + str(details.get("exception", {}).get("description")
                                                   or details.get("text")))
        elif method == "Runtime.consoleAPICalled" and params.get("type") in ("error", "assert"):
            self.errors.append("console: " + " ".join(str(a.get("value", a.get("description")))
                                                      for a in params.get("args", [])))
        elif method == "Log.entryAdded" and params.get("entry", {}).get("level") == "error":
            self.errors.append("log: " + params["entry"].get("text", ""))

    def open(self, url: str, timeout: float = 60.0) -> None:
        """Load a page and wait for its load event."""
        self.call("Page.navigate", url=url)
        deadline = time.monotonic() + timeout
        while True:
            message = json.loads(self._socket.recv(timeout=max(0.1, deadline - time.monotonic())))
            self._event(message)
            if message.get("method") == "Page.loadEventFired":
                return

    def evaluate(self, expression: str):
        """The value of a JavaScript expression in the page."""
        result = self.call("Runtime.evaluate", expression=expression, returnByValue=True)
        return result.get("result", {}).get("value")

    def screenshot(self):
        """The page as an RGB numpy array (height, width, 3)."""
        import numpy as np
        from PIL import Image

        data = base64.b64decode(self.call("Page.captureScreenshot", format="png", timeout=60)["data"])
        return np.asarray(Image.open(io.BytesIO(data)).convert("RGB"))

    def close(self) -> None:
        """Stop Chromium and remove its profile."""
        try:
            self._socket.close()
        except Exception:  # noqa: BLE001 - closing anyway
            pass
        self.process.terminate()
        try:
            self.process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()
        self.log.close()
        shutil.rmtree(self.profile, ignore_errors=True)

    def _log_text(self) -> str:
        self.log.flush()
        return (self.profile / "chromium.log").read_text(errors="replace")[-2000:]
