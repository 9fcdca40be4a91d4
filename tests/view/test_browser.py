"""The view in a real browser: headless Chromium (Debian's package) loads the page that `mobot view`,
`mobot serve --view` and `mobot run --view` serve, and the screenshots must show the world and the
robot where its pose projects, with no console errors. Screenshots are kept in the folder printed
at the start (MOBOT_TEST_ARTEFACTS, default <repo>/.artefacts/view)."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from mobot_cli.cli import invoke
from tests.view.browser import Browser, available

REPO = Path(__file__).resolve().parents[2]
pytest.importorskip("viser", reason="the view extra (viser) is not installed")
if available():
    pytest.skip(available(), allow_module_level=True)

ARTEFACTS = Path(os.environ.get("MOBOT_TEST_ARTEFACTS", REPO / ".artefacts")) / "view"
WIDTH, HEIGHT = 1000, 700
URL = re.compile(r"http://127\.0\.0\.1:\d+/\?token=[\w-]+")  # the token only the owner sees


@pytest.fixture(scope="module", autouse=True)
def artefacts() -> Path:
    ARTEFACTS.mkdir(parents=True, exist_ok=True)
    print(f"\nview screenshots: {ARTEFACTS}")
    return ARTEFACTS


class Mobot:
    """`python -m mobot_cli ARGS` in the background, its output in a file; the page's URL from it."""

    def __init__(self, *args: object, cache: Path):
        self.log_path = Path(tempfile.mkstemp(prefix="mobot-view-", suffix=".log")[1])
        self.log = open(self.log_path, "w+")
        env = {**os.environ, "MOBOT_CACHE_DIR": str(cache)}
        self.process = subprocess.Popen([sys.executable, "-m", "mobot_cli", *map(str, args)], cwd=REPO, env=env,
                                        stdout=self.log, stderr=subprocess.STDOUT)

    def wait_for(self, pattern: str, timeout: float = 120.0) -> re.Match:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            found = re.search(pattern, self.text())
            if found:
                return found
            assert self.process.poll() is None, f"mobot ended early:\n{self.text()}"
            time.sleep(0.1)
        raise AssertionError(f"no {pattern!r} in:\n{self.text()}")

    def text(self) -> str:
        if not self.log.closed:
            self.log.flush()
        return self.log_path.read_text()

    def interrupt(self) -> int:
        self.process.send_signal(signal.SIGINT)
        try:
            return self.process.wait(timeout=30)
        finally:
            self.kill()

    def kill(self) -> None:
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait()
        self.log.close()


def camera(lo, hi) -> SimpleNamespace:
    """Where the page's camera starts, computed by the view's own aim_camera."""
    from mobot_cli.view.panel import aim_camera

    stub = SimpleNamespace(initial_camera=SimpleNamespace())
    aim_camera(stub, lo, hi)
    return stub.initial_camera


def project(cam, point) -> tuple[float, float]:
    """Pixel of a world point for viser's default camera: 75 degrees of vertical field, z up."""
    eye, look = np.array(cam.position, float), np.array(cam.look_at, float)
    forward = (look - eye) / np.linalg.norm(look - eye)
    right = np.cross(forward, (0.0, 0.0, 1.0))
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    d = np.array(point, float) - eye
    f = (HEIGHT / 2) / np.tan(np.radians(75) / 2)
    return WIDTH / 2 + f * (d @ right) / (d @ forward), HEIGHT / 2 - f * (d @ up) / (d @ forward)


def robot_blue(img: np.ndarray, uv: tuple[float, float], radius: int = 25) -> int:
    """How many pixels near ``uv`` have the bundled robot's blue (lit or in shade)."""
    u, v = int(round(uv[0])), int(round(uv[1]))
    patch = img[max(0, v - radius):v + radius, max(0, u - radius):u + radius].astype(int)
    r, g, b = patch[..., 0], patch[..., 1], patch[..., 2]
    return int(((b - r > 70) & (b - g > 40) & (b > 100)).sum())


def warm(img: np.ndarray) -> float:
    """The share of the picture in the height colours of walls and furniture tops."""
    r, b = img[..., 0].astype(int), img[..., 2].astype(int)
    return float(((r > 150) & (r - b > 50)).mean())


def click(browser: Browser, text: str) -> bool:
    """Click the page's button labelled ``text``; False when there is none."""
    return browser.evaluate(
        "(() => { const b = [...document.querySelectorAll('button')].find(b => b.textContent.trim() === "
        f"{json.dumps(text)}); if (!b) return false; b.click(); return true; }})()")


def buttons(browser: Browser) -> list[str]:
    """The labels of the page's buttons."""
    return browser.evaluate("[...document.querySelectorAll('button')].map(b => b.textContent.trim())") or []


def settle(browser: Browser, condition, timeout: float = 90.0):
    """Screenshots until ``condition(image)`` holds; the last image either way."""
    deadline = time.monotonic() + timeout
    while True:
        image = browser.screenshot()
        if condition(image) or time.monotonic() > deadline:
            return image
        time.sleep(1.0)


def hide_notices(browser: Browser) -> None:
    """Close the page's notices (SwiftShader's "software WebGL" one) so the screenshot shows the scene."""
    browser.evaluate("document.querySelectorAll('.mantine-Notification-closeButton').forEach(b => b.click())")


def save(image: np.ndarray, name: str) -> Path:
    from PIL import Image

    path = ARTEFACTS / name
    Image.fromarray(image).save(path, optimize=True)
    return path


@pytest.fixture(scope="module")
def house_run(tmp_path_factory) -> Path:
    """The bundled house scenario, 6 s of it, with a bag (joint states)."""
    out = tmp_path_factory.mktemp("house") / "run"
    outcome = invoke(["run", REPO / "scenarios" / "house.yaml", "--out", out, "--quiet", "--duration", "6",
                      "--set", "log.formats=[csv, mcap]"])
    assert outcome.exit_code == 0, outcome.stderr
    return out


def test_mobot_view_draws_the_house_and_the_robot_then_plays_the_run(house_run, tmp_path_factory):
    from mobot_cli.view.runfolder import read_run
    from mobot_cli.view.world import world_mesh

    run = read_run(house_run)
    mesh = world_mesh(run.plan.world)
    cam = camera(mesh.lo, mesh.hi)
    track = run.tracks[0]
    start, end = track.true[0, :3] + (0, 0, 0.1), track.true[-1, :3] + (0, 0, 0.1)
    assert np.hypot(*(end - start)[:2]) > 2.0  # it drove far enough to tell the two apart
    mobot = Mobot("view", house_run, "--port", 0, cache=tmp_path_factory.getbasetemp() / "mobot-cache")
    try:
        url = mobot.wait_for(URL.pattern).group(0)
        with Browser(WIDTH, HEIGHT) as browser:
            browser.open(url)
            first = settle(browser, lambda img: robot_blue(img, project(cam, start)) >= 40)
            save(first, "view-start.png")
            assert robot_blue(first, project(cam, start)) >= 40, "the robot is not drawn at its start pose"
            assert robot_blue(first, project(cam, end)) < 10
            assert warm(first) > 0.03, "the house's walls are not drawn"
            assert click(browser, "Play")
            hide_notices(browser)
            deadline = time.monotonic() + 60
            for label in ("Pause", "Play"):  # playing, the button says Pause; at the run's end, Play again
                while label not in buttons(browser):
                    assert time.monotonic() < deadline, f"no {label} button: {buttons(browser)}"
                    time.sleep(0.2)
            last = settle(browser, lambda img: robot_blue(img, project(cam, end)) >= 40, timeout=60)
            save(last, "view-end.png")
            assert robot_blue(last, project(cam, end)) >= 40, "the robot did not reach its last pose"
            assert robot_blue(last, project(cam, start)) < 10
            text = browser.evaluate("document.body.innerText")
            assert "mobot" in text and f"{track.true[-1, 0]:.2f}" in text  # the robot list's live numbers
            assert browser.errors == []
    finally:
        assert mobot.interrupt() == 0, mobot.text()


def test_serve_view_pauses_steps_resumes_and_its_pad_drives_the_robot(tmp_path_factory):
    from mobot_cli.live.client import Client

    folder = Path(tempfile.mkdtemp(prefix="mobot-t-"))
    endpoint = f"ipc://{folder}/s.sock"
    mobot = Mobot("serve", REPO / "scenarios" / "quickstart.yaml", "--view", "--view-port", 0, "--endpoint", endpoint,
                  "--duration", 600, cache=tmp_path_factory.getbasetemp() / "mobot-cache")
    try:
        url = mobot.wait_for(URL.pattern).group(0)
        mobot.wait_for("serving 'quickstart'")
        with Browser(WIDTH, HEIGHT) as browser, Client(endpoint, timeout=10) as client:
            browser.open(url)
            deadline = time.monotonic() + 60
            while not click(browser, "Pause"):
                assert time.monotonic() < deadline, "no Pause button"
                time.sleep(0.5)
            time.sleep(0.3)
            held = client.ping()["step"]
            time.sleep(0.5)
            assert client.ping()["step"] == held
            assert click(browser, "Step")  # 24 steps by default: a tenth of a second at 240 Hz
            deadline = time.monotonic() + 20  # a loaded machine (Chromium draws in software) may be slow
            while client.ping()["step"] < held + 24 and time.monotonic() < deadline:
                time.sleep(0.1)
            time.sleep(0.5)
            assert client.ping()["step"] == held + 24  # and not one more
            assert click(browser, "Resume")
            deadline = time.monotonic() + 60  # playing again: the steps go on, however busy the machine
            while client.ping()["step"] <= held + 60 and time.monotonic() < deadline:
                time.sleep(0.1)
            assert client.ping()["step"] > held + 60
            time.sleep(12.5 - client.ping()["t"] if client.ping()["t"] < 12.5 else 0)  # the script is over
            assert click(browser, "▲")  # the first robot is selected: 0.3 m/s for 1 s
            time.sleep(0.3)
            assert client.odom("mobot")["cmd"] == {"linear": 0.3, "angular": 0.0}
            hide_notices(browser)
            save(browser.screenshot(), "serve-view.png")
            assert browser.errors == []
    finally:
        assert mobot.interrupt() == 0, mobot.text()


def test_run_view_is_live_while_the_run_goes_then_replays_it(tmp_path, tmp_path_factory):
    out = tmp_path / "run"
    mobot = Mobot("run", REPO / "scenarios" / "quickstart.yaml", "--view", "--view-port", 0, "--realtime",
                  "--duration", 10, "--out", out, "--quiet", cache=tmp_path_factory.getbasetemp() / "mobot-cache")
    try:
        url = mobot.wait_for(URL.pattern).group(0)
        with Browser(WIDTH, HEIGHT) as browser:
            browser.open(url)
            times = []
            deadline = time.monotonic() + 60
            while len(times) < 2 and time.monotonic() < deadline:
                found = re.search(r"t = (\d+\.\d+) s", browser.evaluate("document.body.innerText") or "")
                if found and (not times or float(found.group(1)) > times[-1]):
                    times.append(float(found.group(1)))
                time.sleep(0.5)
            assert len(times) == 2 and 0 <= times[0] < times[1] < 10, times  # the clock moves while it runs
            mobot.wait_for("run finished; the view stays at")
            deadline = time.monotonic() + 30
            while not click(browser, "Play"):  # the page became a replay of the run folder
                assert time.monotonic() < deadline, "no replay"
                time.sleep(0.5)
            assert browser.errors == []
    finally:
        assert mobot.interrupt() == 0, mobot.text()
    assert json.loads((out / "summary.json").read_text())["status"] == "ok"
