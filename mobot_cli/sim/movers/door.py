"""What a World does with movers (docs/movers.md): the base both engines' Worlds take it from.

The World owns a MoverStage (sim/movers/stage.py) once a mover comes: the world's actors when it
is built, a scenario's movers when the timeline adds them, a live or API request's any time.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mobot_cli.plan import MoverPlan

if TYPE_CHECKING:
    from mobot_cli.sim.movers.stage import MoverStage


class MoversDoor:
    """Movers in a World; the World sets ``_stage`` to None and has ``_cid``, ``physics``, ``plan``,
    ``seed``, ``_steps`` and ``_pristine``."""

    _stage: MoverStage | None

    def _add_actors(self) -> None:
        for actor in self.plan.actors:
            self.add_mover(actor)

    def add_mover(self, plan: MoverPlan) -> None:
        """A mover enters the world now (SpawnError: its name is taken)."""
        if self._stage is None:
            from mobot_cli.sim.movers.stage import MoverStage  # worlds without movers never load it

            self._stage = MoverStage(self._cid, self.physics.rate_hz, self.plan, self.seed)
        self._pristine = False  # the movers' bodies are not the static world's
        self._stage.add(plan, self._steps)

    def remove_mover(self, name: str) -> None:
        """Take a mover out (KeyError: none of that name)."""
        if self._stage is None:
            raise KeyError(f"no mover named '{name}'")
        self._stage.remove(name)

    def movers_moved(self) -> int:
        """A count that changes whenever the movers move, come or go (log rows record them then)."""
        return self._stage.crowd.updates if self._stage is not None else 0

    def movers(self) -> dict[str, tuple[float, float, float]]:
        """Each mover's x, y, yaw now, by name (in the order they came)."""
        return self._stage.crowd.poses() if self._stage is not None else {}

    def mover_plans(self) -> list[MoverPlan]:
        """The plans of the movers in the world, in the order they came."""
        return list(self._stage.crowd.plans) if self._stage is not None else []

    def _is_person(self, other) -> bool:
        """True when a ContactCounter key is a person mover's body."""
        return self._stage is not None and other[0] == "body" and other[1] in self._stage.people
