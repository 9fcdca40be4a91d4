"""Playing or paused: the live world's SimulationState, and the steps a paused world still owes.

One Lockstep per live world. The protocol's ``pause``, ``resume`` and ``step`` requests and the
`serve --view` page's buttons (another thread) press the same one, so they always agree. The
server's loop asks ``hold()`` before each physics step and ``spend()`` when it takes one: a
paused world takes exactly the steps it was asked for, as fast as it can, then waits again.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from typing import Any, Callable

from mobot_cli.live import protocol
from mobot_cli.live.protocol import Feature, Refusal, Result, SimulationState

SPAWN_FORMATS = ("urdf", "xacro", "sdf")


@dataclass
class Owed:
    """A reply the server owes at step ``until``: a `step`, or a `cmd --wait`."""

    envelope: list[bytes]
    request: Any
    until: int
    answer: Callable[[], dict[str, Any]]


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


class LockstepRequests:
    """The server's answers to pause, resume, step, reset, get_state, set_state and features."""

    def __init__(self, server: Any):
        self.server = server  # live.server.LiveServer: its session, control, history and owed replies

    def handlers(self) -> dict[str, Callable]:
        """op -> handler(envelope, request), as the server calls them."""
        return {"pause": self.pause, "resume": self.resume, "step": self.step, "reset": self.reset,
                "get_state": self.get_state, "set_state": self.set_state,
                "features": lambda envelope, request: features_reply(request.id, self.server.control)}

    def pause(self, envelope, request) -> dict[str, Any]:
        """SetSimulationState(PAUSED), idempotent."""
        return self._set(request, self.server.control.pause(), "pause")

    def resume(self, envelope, request) -> dict[str, Any]:
        """SetSimulationState(PLAYING), idempotent."""
        return self._set(request, self.server.control.resume(), "resume")

    def _set(self, request, changed: bool, op: str) -> dict[str, Any]:
        if changed:
            self.server.history(op=op, result="OK")
        return protocol.reply(request.id, changed=changed, **self.server.now(), **self.server.control.fields())

    def step(self, envelope, request) -> None:
        """StepSimulation: only while paused; the reply comes once the steps are taken."""
        server = self.server
        count = steps_of(request.steps, request.seconds, server.plan.physics.rate_hz)
        if not server.control.paused:
            raise Refusal(Result.INCORRECT_STATE, "the world is playing: step only a paused world "
                          "(pause it first, or start it with `mobot serve --paused`)")
        until = server.session.step + server.control.budget + count
        server.control.step(count)

        def done() -> dict[str, Any]:
            states = {"robots": server.session.states()} if request.states else {}
            return protocol.reply(request.id, steps=count, **server.now(), **server.control.fields(), **states)

        server.owe(Owed(envelope, request, until, done))

    def reset(self, envelope, request) -> dict[str, Any]:
        """ResetSimulation (SCOPE_ALL): replies still owed end first, then the world starts over."""
        server = self.server
        server.control.clear()
        server.answer_owed(waits_only=True, why="the world was reset before this request finished")
        server.session.reset()
        return protocol.reply(request.id, **server.now(), resets=server.session.timeline.resets,
                              robots=list(server.session.robots), **server.control.fields())

    def get_state(self, envelope, request) -> dict[str, Any]:
        """GetEntityState."""
        return self.server.session.entity_state(request.id, request.name, request.reference_frame)

    def set_state(self, envelope, request) -> dict[str, Any]:
        """SetEntityState: a teleport."""
        return self.server.session.teleport(request)
