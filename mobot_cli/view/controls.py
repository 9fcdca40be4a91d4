"""`mobot serve --view`: buttons that pause, resume and step the world, and a teleop pad.

The page talks to the world through ``WorldControl``, a small interface: the CLI wires it to the
live server's own pause state (its Lockstep, which the protocol's pause, resume and step requests
press too, so the page and every client always agree) and to ordinary `cmd` requests for the pad,
which therefore show in history.jsonl like any client's.

Whatever the page sends is bounded here, not by its widgets: a websocket client can set any
number into them. Speeds are clamped to the pad's sliders, a Step click takes at most
``max_steps`` (`serve --view-max-steps`), and Pause also drops the steps a Step still owes.
"""

from __future__ import annotations

import math
from typing import Any, Callable, Protocol

DRIVE_FOR_S = 1.0  # each press of the pad drives this long, then the robot stops (a lost page stops it)
MAX_LINEAR = 2.0  # m/s, the speed slider's top: a wheeled robot's pace, not a projectile's
MAX_ANGULAR = 3.0  # rad/s, the turn slider's top
DEFAULT_MAX_STEPS = 10_000  # physics steps one Step click may take


def bounded(value: Any, low: float, high: float, fallback: float) -> float:
    """``value`` as a float within [low, high]; ``fallback`` when it is no finite number."""
    try:
        number = float(value)
    except (TypeError, ValueError, OverflowError):
        return fallback
    return min(max(number, low), high) if math.isfinite(number) else fallback


class WorldControl(Protocol):
    """What the page may ask of a live world."""

    def pause(self) -> None: ...

    def resume(self) -> None: ...

    def step(self, steps: int = 1) -> None: ...

    @property
    def paused(self) -> bool: ...

    def command(self, name: str, linear: float, angular: float, seconds: float) -> str | None:
        """Drive a robot for ``seconds``; returns why it was refused, or None."""


class PauseState(Protocol):
    """The live world's pause state (live.lockstep.Lockstep): thread-safe, pressed from the page's thread."""

    @property
    def paused(self) -> bool: ...

    def pause(self) -> Any: ...

    def clear(self) -> Any: ...

    def resume(self) -> Any: ...

    def step(self, steps: int = 1) -> Any: ...


class GateControl:
    """WorldControl over the world's pause state and a function that sends `cmd` requests."""

    def __init__(self, gate: PauseState, send_cmd: Callable[[str, float, float, float], str | None]):
        self.gate, self._send = gate, send_cmd

    @property
    def paused(self) -> bool:
        return self.gate.paused

    def pause(self) -> None:
        # A Step click may owe many steps; the page's Pause means stop now, so it drops them.
        self.gate.pause()
        self.gate.clear()

    def resume(self) -> None:
        self.gate.resume()

    def step(self, steps: int = 1) -> None:
        self.gate.step(steps)

    def command(self, name: str, linear: float, angular: float, seconds: float) -> str | None:
        return self._send(name, linear, angular, seconds)


def add_controls(server: Any, control: WorldControl, selected: Callable[[], str | None], rate_hz: int,
                 max_steps: int = DEFAULT_MAX_STEPS) -> Any:
    """The World folder (pause, resume, step) and the Teleop folder (a pad for the selected robot)."""
    gui = server.gui
    first = min(max(1, rate_hz // 10), max_steps)
    with gui.add_folder("World"):
        run = gui.add_button_group("world", ("Pause", "Resume", "Step"))
        steps = gui.add_number("steps per Step", initial_value=first, min=1, max=max_steps, step=1)
        state = gui.add_markdown("paused" if control.paused else "running")
    with gui.add_folder("Teleop"):
        speed = gui.add_slider("speed (m/s)", min=0.05, max=MAX_LINEAR, step=0.05, initial_value=0.3)
        turn = gui.add_slider("turn (rad/s)", min=0.1, max=MAX_ANGULAR, step=0.1, initial_value=0.8)
        pad = gui.add_button_group("drive", ("◀", "▲", "■", "▼", "▶"))
        reply = gui.add_markdown("select a robot under Robots")

    @run.on_click
    def _(event: Any) -> None:
        {"Pause": control.pause, "Resume": control.resume,
         "Step": lambda: control.step(int(bounded(steps.value, 1, max_steps, 1)))}.get(run.value, lambda: None)()
        state.content = "paused" if control.paused else "running"

    @pad.on_click
    def _(event: Any) -> None:
        name = selected()
        if name is None:
            reply.content = "select a robot under Robots first"
            return
        v, w = bounded(speed.value, 0.0, MAX_LINEAR, 0.0), bounded(turn.value, 0.0, MAX_ANGULAR, 0.0)
        linear, angular = {"▲": (v, 0.0), "▼": (-v, 0.0), "◀": (0.0, w), "▶": (0.0, -w),
                           "■": (0.0, 0.0)}.get(pad.value, (0.0, 0.0))
        refused = control.command(name, float(linear), float(angular), DRIVE_FOR_S)
        reply.content = refused or f"{name}: {linear:g} m/s, {angular:g} rad/s for {DRIVE_FOR_S:g} s"

    return state
