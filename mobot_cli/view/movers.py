"""Movers in the browser view (docs/movers.md): each one its shape, where it is now.

A person is drawn as an upright cylinder of its capsule's radius and height (viser has no
capsule), a box as its box, turned by its heading.
"""

from __future__ import annotations

import math
from typing import Any, Callable

from mobot_cli.plan import MoverPlan

PERSON_COLOR = (230, 140, 60)
OBJECT_COLOR = (140, 140, 150)


class MoverShapes:
    """The movers' shapes in one viser scene; ``show`` moves, adds and removes them."""

    def __init__(self, server: Any, plans: Callable[[], list[MoverPlan]]):
        self.server, self.plans = server, plans
        self.handles: dict[str, tuple[Any, float]] = {}  # name -> (handle, the height of its centre)

    def show(self, poses: dict[str, tuple[float, float, float]]) -> None:
        """Every mover at its pose (x, y, yaw); those no longer in ``poses`` go."""
        for name in [n for n in self.handles if n not in poses]:
            self.handles.pop(name)[0].remove()
        missing = [name for name in poses if name not in self.handles]
        if missing:
            by_name = {plan.name: plan for plan in self.plans()}
            for name in missing:
                if name in by_name:
                    self.handles[name] = self._add(by_name[name])
        for name, (x, y, yaw) in poses.items():
            entry = self.handles.get(name)
            if entry is not None:
                handle, z = entry
                handle.position = (x, y, z)
                handle.wxyz = (math.cos(yaw / 2.0), 0.0, 0.0, math.sin(yaw / 2.0))

    def _add(self, plan: MoverPlan) -> tuple[Any, float]:
        scene, name = self.server.scene, f"/movers/{plan.name}"
        if plan.shape == "box":
            height = plan.size[2]
            handle = scene.add_box(name, OBJECT_COLOR, tuple(plan.size), cast_shadow=False)
        else:
            height = plan.size[1]
            color = PERSON_COLOR if plan.shape == "person" else OBJECT_COLOR
            handle = scene.add_cylinder(name, plan.size[0], height, color, cast_shadow=False)
        return handle, plan.z + height / 2.0
