"""The selected robot's camera in the live view's panel, in a real headless Chromium."""

from __future__ import annotations

import time

import pytest

from tests.view.browser import Browser, available
from tests.view.test_browser import HEIGHT, URL, WIDTH, Mobot

pytest.importorskip("viser", reason="the view extra (viser) is not installed")
if available():
    pytest.skip(available(), allow_module_level=True)

SCENARIO = """version: 1
name: eyes
world: empty
duration: 20.0
robots:
  - name: mobot
    args: {camera: "true"}
    commands: [{at: 0.5, angular: 0.5}]
"""
IMAGES = "[...document.querySelectorAll('img')].filter(i => i.naturalWidth === 320 && i.naturalHeight === 240).length"


def test_the_selected_robots_camera_shows_in_the_panel(tmp_path, tmp_path_factory):
    (tmp_path / "eyes.yaml").write_text(SCENARIO)
    mobot = Mobot("run", tmp_path / "eyes.yaml", "--view", "--view-port", 0, "--realtime", "--out", tmp_path / "run",
                  "--quiet", cache=tmp_path_factory.getbasetemp() / "mobot-cache")
    try:
        url = mobot.wait_for(URL.pattern).group(0)
        with Browser(WIDTH, HEIGHT) as browser:
            browser.open(url)
            deadline, shown = time.monotonic() + 60, 0
            while not shown and time.monotonic() < deadline:
                shown = browser.evaluate(IMAGES) or 0
                time.sleep(0.5)
            assert shown == 1  # the bundled robot's 320 x 240 camera, the robot selected as the first
            assert browser.errors == []
    finally:
        mobot.interrupt()
