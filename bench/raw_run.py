#!/usr/bin/env python3
"""The raw PyBullet loop mobot is measured against: nothing but PyBullet calls, no mobot import.

The same physics a mobot run of the bundled robot does (mobot_cli/sim/bullet/world.py's engine
settings, velocity motors set when the command changes, base state and wheel joints read and a
CSV row written at the log rate). ``bench_run.py`` calls ``raw_loop`` in its own process, and
runs this file as a whole process to time the raw loop's fixed cost (interpreter, PyBullet's
import, the URDF's load) beside ``mobot run``'s:

    python3 bench/raw_run.py SPEC.json OUT_DIR   # prints the loop's own wall seconds
    python3 bench/raw_run.py SPEC.json OUT_DIR --libraries   # the same, importing mobot's libraries first

``--libraries`` imports what any `mobot run` imports before it does anything of its own (Typer,
which builds its parameters with pydantic, pydantic itself, PyYAML and Pillow) and then runs the
same loop: the floor a command line built on these libraries starts from.

SPEC.json holds what ``spec(plan)`` in bench_run.py writes: the URDF path, poses, rates, the
drive's joints and the one command.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import pybullet as p


def raw_loop(spec: dict, out_dir: Path) -> float:
    """Run the spec's robots to its last step, a CSV per robot in ``out_dir``; the loop's wall seconds
    (from the first step to the last, as mobot's loop is timed)."""
    cid = p.connect(p.DIRECT)
    p.setPhysicsEngineParameter(fixedTimeStep=1.0 / spec["rate_hz"], numSolverIterations=spec["solver_iterations"],
                                numSubSteps=0, deterministicOverlappingPairs=1, enableConeFriction=0,
                                physicsClientId=cid)
    p.setGravity(*spec["gravity"], physicsClientId=cid)
    plane = p.createMultiBody(0, p.createCollisionShape(p.GEOM_PLANE, physicsClientId=cid), physicsClientId=cid)
    p.changeDynamics(plane, -1, lateralFriction=1.0, physicsClientId=cid)
    bodies = []
    for name, xyz, quat in spec["robots"]:
        uid = p.loadURDF(spec["urdf"], xyz, quat, physicsClientId=cid,
                         flags=p.URDF_USE_INERTIA_FROM_FILE | p.URDF_USE_IMPLICIT_CYLINDER)
        names = {p.getJointInfo(uid, j, physicsClientId=cid)[1].decode(): j
                 for j in range(p.getNumJoints(uid, physicsClientId=cid))}
        for link in range(-1, len(names)):
            p.changeDynamics(uid, link, lateralFriction=1.0, linearDamping=0.0, angularDamping=0.0,
                             activationState=p.ACTIVATION_STATE_DISABLE_SLEEPING, physicsClientId=cid)
        wheels = [names[n] for n in spec["wheels"]]
        bodies.append((uid, wheels, open(out_dir / f"{name}.csv", "w")))
    half, radius = spec["wheel_separation"] / 2, spec["wheel_radius"]
    at, linear, angular = spec["command"]
    rates = [(linear - angular * half) / radius, (linear + angular * half) / radius]
    total, every, rate = spec["total_steps"], spec["log_every"], spec["rate_hz"]
    started = time.perf_counter()
    for step in range(total + 1):
        if step == at:
            for uid, wheels, _ in bodies:
                p.setJointMotorControlArray(uid, wheels, p.VELOCITY_CONTROL, targetVelocities=rates,
                                            forces=[spec["max_wheel_torque"]] * 2, physicsClientId=cid)
        if step % every == 0:
            for uid, wheels, f in bodies:
                pos, orn = p.getBasePositionAndOrientation(uid, physicsClientId=cid)
                lin, ang = p.getBaseVelocity(uid, physicsClientId=cid)
                joints = p.getJointStates(uid, wheels, physicsClientId=cid)
                rpy = p.getEulerFromQuaternion(orn)
                values = (step / rate, *pos, *rpy, *lin, *ang, joints[0][0], joints[1][0])
                f.write(",".join(f"{v:.6f}" for v in values) + "\n")
        if step < total:
            p.stepSimulation(physicsClientId=cid)
    loop = time.perf_counter() - started
    for _, _, f in bodies:
        f.close()
    p.disconnect(cid)
    return loop


def import_libraries() -> None:
    """What a `mobot run` process imports of its chosen libraries before any mobot code runs."""
    import PIL.Image  # noqa: F401
    import PIL.ImageDraw  # noqa: F401
    import PIL.ImageFont  # noqa: F401
    import pydantic
    import typer  # noqa: F401
    import yaml  # noqa: F401

    pydantic.TypeAdapter(int)  # Typer coerces each parameter through a pydantic TypeAdapter


if __name__ == "__main__":
    if "--libraries" in sys.argv[3:]:
        import_libraries()
    print(f"{raw_loop(json.loads(Path(sys.argv[1]).read_text()), Path(sys.argv[2])):.6f}")
