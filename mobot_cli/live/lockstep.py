"""Playing or paused: the live world's SimulationState, and the steps a paused world still owes.

One Lockstep per live world. The protocol's ``pause``, ``resume`` and ``step`` requests and the
`serve --view` page's buttons (another thread) press the same one, so they always agree. The
server's loop asks ``hold()`` before each physics step and ``spend()`` when it takes one: a
paused world takes exactly the steps it was asked for, as fast as it can, then waits again.
"""

from __future__ import annotations

import threading
from typing import Any

from mobot_cli.live import protocol
from mobot_cli.live.protocol import Feature, Refusal, Result, SimulationState

SPAWN_FORMATS = ("urdf", "xacro")


class Lockstep:
    """Thread-safe pause state with a budget of steps to take while paused."""

    def __init__(self, paused: bool = False):
        self._lock = threading.Lock()
        self._paused, self._budget = paused, 0

    @property
    def paused(self) -> bool:
        return self._paused

    @property
    def state(self) -> SimulationState:
        return SimulationState.PAUSED if self._paused else SimulationState.PLAYING

    @property
    def budget(self) -> int:
        """Steps a paused world still has to take."""
        return self._budget

    def pause(self) -> bool:
        """Pause (steps already asked for are still taken); False when it was paused already."""
        with self._lock:
            changed, self._paused = not self._paused, True
            return changed

    def resume(self) -> bool:
        """Play on; False when it was playing already."""
        with self._lock:
            changed, self._paused, self._budget = self._paused, False, 0
            return changed

    def step(self, steps: int = 1) -> int:
        """While paused, let ``steps`` more physics steps through; the budget after (0: playing)."""
        with self._lock:
            if self._paused:
                self._budget += max(0, steps)
            return self._budget

    def hold(self) -> bool:
        """True while the world must wait for a request."""
        return self._paused and self._budget == 0

    def spend(self) -> bool:
        """Count a step about to be taken; True when it is one of a paused world's budget."""
        if not self._paused:
            return False
        with self._lock:
            if self._budget > 0:
                self._budget -= 1
                return True
            return False

    def clear(self) -> None:
        """Drop the steps still owed (a reset)."""
        with self._lock:
            self._budget = 0

    def fields(self) -> dict[str, Any]:
        """The state as reply fields: its name (as SimulationState's, lower case) and number."""
        state = self.state
        return {"state": state.name.lower(), "state_code": int(state)}


def steps_of(steps: int | None, seconds: float | None, rate_hz: int) -> int:
    """A step request's whole number of steps; INVALID_REQUEST for a duration that is not one."""
    from mobot_cli.live.schema import MAX_STEPS

    if seconds is None:
        return 1 if steps is None else steps
    exact = seconds * rate_hz
    if not exact <= MAX_STEPS:  # also infinity
        raise Refusal(Result.INVALID_REQUEST, f"{seconds:g} s is {exact:g} steps at {rate_hz} Hz; a step "
                      f"request takes at most {MAX_STEPS}")
    nearest = max(1, round(exact))
    # Seconds given as decimals (0.1 at 240 Hz is 24.000000000000004 steps) are whole within rounding.
    if abs(exact - nearest) > 1e-9 * max(1.0, exact):
        raise Refusal(Result.INVALID_REQUEST, f"{seconds:g} s is {exact:g} steps at {rate_hz} Hz, not a whole "
                      f"number: the nearest is {nearest} step(s) ({nearest / rate_hz:g} s); time moves in "
                      "whole physics steps")
    return nearest


def features_reply(request_id: Any, control: Lockstep) -> dict[str, Any]:
    """GetSimulatorFeatures: the features by number and name, the spawn formats and the ops."""
    return protocol.reply(request_id, features=[{"id": int(f), "name": f.name} for f in Feature],
                          spawn_formats=list(SPAWN_FORMATS), ops=list(protocol.OPS),
                          custom_info="mobot live world: see the README's 'Lockstep control'",
                          **control.fields())
