"""`--ros2` for `mobot run` and `mobot serve`: the bridge is imported only when it is asked for."""

from __future__ import annotations

from typing import TYPE_CHECKING

from mobot_cli.cli.environment import Environment
from mobot_cli.errors import Location

if TYPE_CHECKING:  # the plan's module is imported by the commands that make one, not by every command's start
    from mobot_cli.plan import Plan

# The --ros2 option's help; run.py and serve.py declare the option.
HELP = ("Join ROS 2 as node 'mobot': publish /clock, /tf, odom, joint_states, robot_description; "
        "take cmd_vel (extra 'ros2'; domain ROS_DOMAIN_ID).")


def bridges(plan: Plan, asked: bool) -> list:
    """The ROS 2 bridge when ``--ros2`` or the scenario's ``ros2:`` asks for one, checked now."""
    if not asked and plan.ros2 is None:
        return []
    from mobot_cli.plan import Ros2Settings
    from mobot_cli.ros2.bridge import Bridge

    where = Location(key="ros2") if plan.ros2 is not None else None
    return [Bridge(plan, plan.ros2 or Ros2Settings(), where=where)]


def joined(env: Environment, bridges: list, quiet: bool) -> None:
    """One line: which domain and node the world joined."""
    if quiet:
        return
    for bridge in bridges:
        node = bridge.settings.namespace.rstrip("/") + "/" + bridge.settings.node
        env.stderr.write(f"mobot: ROS 2: node {node} in domain {bridge.domain_id} (set use_sim_time:=true)\n")


def report(env: Environment, bridges: list, quiet: bool) -> None:
    """What each bridge sent, and whether it broke on the way; a bridge the run never opened
    (it stopped before) leaves the domain here."""
    for bridge in bridges:
        stats = bridge.close()
        if stats.error:
            env.stderr.write(f"mobot: warning: ROS 2 publishing stopped: {stats.error}\n")
        for line in stats.left_out:
            env.stderr.write(f"mobot: warning: {line}\n")
        if not quiet:
            dropped = f", {stats.dropped_samples} sample(s) dropped" if stats.dropped_samples else ""
            refused = sum(n for _, n in stats.dropped_input)
            dropped += f", {refused} cmd_vel sample(s) refused (see summary.json's notices)" if refused else ""
            env.stderr.write(f"mobot: ROS 2: {stats.messages} message(s) sent, {stats.commands} cmd_vel "
                             f"taken{dropped}\n")


def services(env: Environment, bridges: list, endpoint: str, rate_hz: int, quiet: bool) -> list:
    """`serve --ros2`: the simulation_interfaces services on rclpy, when rclpy and the
    simulation_interfaces package import; otherwise one line says why there are none."""
    if not bridges:
        return []
    from mobot_cli.ros2 import sim_services

    why = sim_services.available()
    bridge = bridges[0]
    if why is None:
        try:
            return [sim_services.SimulationServices(endpoint, bridge.settings.node,
                                                    bridge.settings.namespace, bridge.domain_id, rate_hz)]
        except Exception as exc:  # noqa: BLE001 - rclpy's own errors (RMW, domain): the world goes on
            why = f"rclpy could not start them ({type(exc).__name__}: {exc})"
    if not quiet:
        env.stderr.write(f"mobot: ROS 2: topics only, no simulation_interfaces services: {why}\n")
    return []


def close_services(started: list) -> None:
    """Leave the ROS graph (the services node)."""
    for node in started:
        node.close()
