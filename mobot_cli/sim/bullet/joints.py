"""Springs and held joints of one robot body, as Gazebo keeps them (plan.JointHold).

A held joint gets a PyBullet position motor to its target with its effort limit, as a position
controller would; PyBullet keeps a motor between steps, so nothing runs per step.

A spring is a position motor to its reference whose force limit is reset before every step to
the spring's force there, stiffness * |q - reference|: it pushes as the spring does, and being a
constraint of the solver it never pushes past the reference. A spring torque (TORQUE_CONTROL,
-stiffness * (q - reference)) is the same force applied explicitly, and it launched
tests/sim/robots/spring_caster.urdf.xacro (a 0.3 kg caster, 240 Hz): 36 m away while driving
at 2e5 N/m, 300 m in 3 s at rest at 2e6 N/m. The motor stays put at both and agrees with the
torque where that is stable (2e4 N/m: 2.1 mm of travel, 0.35 deg of pitch, both ways). The
spring's damping is the URDF's <dynamics damping>, which PyBullet applies itself.
"""

from __future__ import annotations

from mobot_cli.plan import JointHold
from mobot_cli.sim.pb import p


class JointHolds:
    """The holds of one robot body: motors set once, spring torques every step."""

    def __init__(self, cid: int, body: int, joints: dict[str, int], holds: tuple[JointHold, ...],
                 skip: set[str]):
        self.cid = cid
        self.body = body
        mine = [h for h in holds if h.joint in joints and h.joint not in skip]
        held = [h for h in mine if h.kind == "position"]
        if held:
            p.setJointMotorControlArray(
                body, [joints[h.joint] for h in held], p.POSITION_CONTROL,
                targetPositions=[h.target for h in held], forces=[h.effort for h in held],
                physicsClientId=cid)
        springs = [h for h in mine if h.kind == "spring"]
        self.spring_joints = [joints[h.joint] for h in springs]
        self.stiffness = [h.stiffness for h in springs]
        self.reference = [h.target for h in springs]

    def apply_springs(self) -> None:
        """Spring torques for the next step (call before every step while springs exist)."""
        states = p.getJointStates(self.body, self.spring_joints, physicsClientId=self.cid)
        forces = [k * abs(s[0] - ref) for s, k, ref in zip(states, self.stiffness, self.reference)]
        n = len(forces)
        p.setJointMotorControlArray(self.body, self.spring_joints, p.POSITION_CONTROL, targetPositions=self.reference,
                                    forces=forces, positionGains=[1.0] * n, velocityGains=[1.0] * n,
                                    physicsClientId=self.cid)


def set_initial_positions(cid: int, body: int, holds: tuple[JointHold, ...]) -> None:
    """Start held joints at their targets (a ros2_control initial_value), before placement."""
    index = {p.getJointInfo(body, j, physicsClientId=cid)[1].decode(): j
             for j in range(p.getNumJoints(body, physicsClientId=cid))}
    for hold in holds:
        if hold.kind == "position" and hold.target != 0.0 and hold.joint in index:
            p.resetJointState(body, index[hold.joint], hold.target, physicsClientId=cid)
