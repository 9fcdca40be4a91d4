"""A small Ackermann car of our own (0.5 m wheelbase, 0.4 m track, 0.1 m wheels), as URDF text.

The root link sits mid-car, 0.25 m ahead of the rear axle, so odometry and arcs must account for
the lever arm. Steering joints are limited to +-0.6 rad; ``gazebo`` is the <gazebo> block added.
"""

from __future__ import annotations

WHEELBASE, TRACK, RADIUS = 0.5, 0.4, 0.1

GAZEBO_ROS = """<gazebo><plugin name="gazebo_ros_ackermann_drive" filename="libgazebo_ros_ackermann_drive.so">
  <update_rate>100.0</update_rate>
  <front_left_joint>front_left_wheel_joint</front_left_joint>
  <front_right_joint>front_right_wheel_joint</front_right_joint>
  <rear_left_joint>rear_left_wheel_joint</rear_left_joint>
  <rear_right_joint>rear_right_wheel_joint</rear_right_joint>
  <left_steering_joint>left_steering_joint</left_steering_joint>
  <right_steering_joint>right_steering_joint</right_steering_joint>
  <max_steer>0.45</max_steer>
  <max_speed>5</max_speed>
  <publish_odom>true</publish_odom>
</plugin></gazebo>"""

GZ = """<gazebo><plugin filename="gz-sim-ackermann-steering-system" name="gz::sim::systems::AckermannSteering">
  <left_joint>rear_left_wheel_joint</left_joint>
  <right_joint>rear_right_wheel_joint</right_joint>
  <left_steering_joint>left_steering_joint</left_steering_joint>
  <right_steering_joint>right_steering_joint</right_steering_joint>
  <kingpin_width>0.4</kingpin_width>
  <steering_limit>0.5</steering_limit>
  <wheel_base>0.5</wheel_base>
  <wheel_separation>0.4</wheel_separation>
  <wheel_radius>0.1</wheel_radius>
  <min_velocity>-2</min_velocity>
  <max_velocity>2</max_velocity>
</plugin></gazebo>"""

TRACKED = """<gazebo><plugin filename="gz-sim-tracked-vehicle-system" name="gz::sim::systems::TrackedVehicle">
  <left_track><link>left_track</link></left_track><right_track><link>right_track</link></right_track>
  <tracks_separation>0.4</tracks_separation>
</plugin></gazebo>"""


def _inertial(mass: float, i: float) -> str:
    return (f'<inertial><mass value="{mass}"/><inertia ixx="{i}" ixy="0" ixz="0" iyy="{i}" iyz="0" '
            f'izz="{i}"/></inertial>')


def _wheel(name: str, parent: str, xyz: str, mesh: str = "") -> str:
    geometry = (f'<mesh filename="{mesh}"/>' if mesh else f'<cylinder radius="{RADIUS}" length="0.05"/>')
    return (f'<link name="{name}_wheel">{_inertial(0.5, 0.002)}<collision><origin rpy="1.5707963267948966 0 0"/>'
            f'<geometry>{geometry}</geometry></collision></link>'
            f'<joint name="{name}_wheel_joint" type="continuous"><parent link="{parent}"/>'
            f'<child link="{name}_wheel"/><origin xyz="{xyz}"/><axis xyz="0 1 0"/></joint>')


def _knuckle(side: str, y: float, limit: float, axis: str) -> str:
    return (f'<link name="{side}_knuckle">{_inertial(0.2, 0.0005)}</link>'
            f'<joint name="{side}_steering_joint" type="revolute"><parent link="base_link"/>'
            f'<child link="{side}_knuckle"/><origin xyz="{WHEELBASE / 2} {y} {RADIUS}"/>'
            f'<axis xyz="{axis}"/><limit lower="-{limit}" upper="{limit}" effort="50" velocity="5"/></joint>')


def car(gazebo: str = "", *, limit: float = 0.6, mesh: str = "", steer_axis: str = "0 0 1") -> str:
    """The car's URDF text with ``gazebo`` (a <gazebo> block) added."""
    half, rear = TRACK / 2, -WHEELBASE / 2
    return (f'<?xml version="1.0"?>\n<robot name="car"><link name="base_link">{_inertial(8.0, 0.2)}'
            f'<collision><origin xyz="0 0 {RADIUS + 0.08}"/><geometry><box size="0.7 0.3 0.1"/></geometry>'
            f'</collision></link>'
            + _knuckle("left", half, limit, steer_axis) + _knuckle("right", -half, limit, steer_axis)
            + _wheel("front_left", "left_knuckle", "0 0 0", mesh)
            + _wheel("front_right", "right_knuckle", "0 0 0", mesh)
            + _wheel("rear_left", "base_link", f"{rear} {half} {RADIUS}", mesh)
            + _wheel("rear_right", "base_link", f"{rear} {-half} {RADIUS}", mesh)
            + gazebo + "</robot>\n")


if __name__ == "__main__":  # writes tests/sim/robots/ackermann_car.urdf (the docs' car)
    from pathlib import Path

    Path(__file__).with_name("robots").joinpath("ackermann_car.urdf").write_text(car(GAZEBO_ROS))
