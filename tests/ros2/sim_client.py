"""A real rclpy client (the RMW rclpy picks: Fast DDS with the wheels) of mobot's simulation_interfaces.

It knows nothing of mobot: it calls each service by its standard type and prints one JSON
document of what came back (result codes, messages, names, poses, stamps, feedback). Run by
tests/ros2/test_sim_services.py with a Python that has rclpy and simulation_interfaces:

    python tests/ros2/sim_client.py PLAN.json     # a list of [label, service, fields] calls
"""

from __future__ import annotations

import json
import sys
import time

import rclpy
from rclpy.action import ActionClient
from simulation_interfaces import action, msg, srv

WAIT = 60.0  # s for a service to appear, and for a reply (a cold spawn on a busy machine)


def _set(message, fields: dict) -> None:
    """Fill a message from nested dicts and lists (lists of dicts become lists of messages)."""
    for key, value in fields.items():
        if isinstance(value, dict):
            _set(getattr(message, key), value)
        elif isinstance(value, list) and value and isinstance(value[0], dict):
            items = []  # the one list of messages in these requests: EntityFilters.categories
            for item in value:
                element = msg.EntityCategory()
                _set(element, item)
                items.append(element)
            setattr(message, key, items)
        else:
            setattr(message, key, value)


def _plain(message):
    """A message as JSON-ready values."""
    if hasattr(message, "get_fields_and_field_types"):
        return {name: _plain(getattr(message, name)) for name in message.get_fields_and_field_types()}
    if isinstance(message, (list, tuple)) or type(message).__name__ in ("array", "ndarray"):
        return [_plain(item) for item in message]
    return message


def call(node, clients: dict, service: str, fields: dict) -> dict:
    kind = getattr(srv, "".join(part.title() for part in service.split("_")))
    client = clients.get(service)
    if client is None:
        client = clients[service] = node.create_client(kind, "/" + service)
        if not client.wait_for_service(timeout_sec=WAIT):
            return {"error": f"/{service} did not appear"}
    request = kind.Request()
    _set(request, fields)
    future = client.call_async(request)
    rclpy.spin_until_future_complete(node, future, timeout_sec=WAIT)
    if not future.done():
        return {"error": f"/{service}: no reply within {WAIT} s"}
    return _plain(future.result())


def simulate_steps(node, steps: int) -> dict:
    """Send a SimulateSteps goal; its feedback is read from the action's feedback topic itself, as
    every message the server published: rclpy's goal handle drops the feedback that trails the
    result (seen on a loaded machine, where only the first of three came through the handle)."""
    client = ActionClient(node, action.SimulateSteps, "/simulate_steps")
    if not client.wait_for_server(timeout_sec=WAIT):
        return {"error": "/simulate_steps did not appear"}
    topic = "/simulate_steps/_action/feedback"
    published: list[tuple[bytes, list[int]]] = []
    node.create_subscription(action.SimulateSteps.Impl.FeedbackMessage, topic, lambda m: published.append(
        (bytes(m.goal_id.uuid), [m.feedback.completed_steps, m.feedback.remaining_steps])), 10)
    deadline = time.monotonic() + WAIT
    while node.count_publishers(topic) == 0 and time.monotonic() < deadline:
        rclpy.spin_once(node, timeout_sec=0.05)
    goal = client.send_goal_async(action.SimulateSteps.Goal(steps=steps))
    rclpy.spin_until_future_complete(node, goal, timeout_sec=WAIT)
    handle = goal.result()
    if handle is None or not handle.accepted:
        return {"error": "goal not accepted"}
    result = handle.get_result_async()
    rclpy.spin_until_future_complete(node, result, timeout_sec=WAIT)
    mine = bytes(handle.goal_id.uuid)

    def feedback() -> list[list[int]]:
        return [values for goal_id, values in published if goal_id == mine]

    deadline = time.monotonic() + 10.0  # feedback comes on a topic of its own: it may trail the result
    while len(feedback()) < steps and time.monotonic() < deadline and result.result().status == 4:
        rclpy.spin_once(node, timeout_sec=0.1)
    return {"status": result.result().status, "result": _plain(result.result().result), "feedback": feedback()}


def publish(node, topic: str, stamped: bool, linear: float, angular: float, seconds: float) -> dict:
    """Publish cmd_vel as Twist (Jazzy's nav2) or TwistStamped (Kilted's) at 20 Hz for ``seconds``."""
    from geometry_msgs.msg import Twist, TwistStamped

    publisher = node.create_publisher(TwistStamped if stamped else Twist, topic, 10)
    deadline = time.monotonic() + 30.0
    while publisher.get_subscription_count() == 0 and time.monotonic() < deadline:
        rclpy.spin_once(node, timeout_sec=0.05)
    matched = publisher.get_subscription_count()
    end, sent = time.monotonic() + seconds, 0
    while time.monotonic() < end:
        twist = Twist()
        twist.linear.x, twist.angular.z = linear, angular
        if stamped:
            message = TwistStamped()
            message.header.frame_id, message.twist = "base_link", twist
        else:
            message = twist
        publisher.publish(message)
        sent += 1
        time.sleep(0.05)
    return {"matched": matched, "sent": sent}


def parameters(node, target: str) -> dict:
    """rclpy's own parameter client on ``target``: list, get use_sim_time, and a set it may refuse."""
    from rclpy.parameter import Parameter
    from rclpy.parameter_client import AsyncParameterClient

    client = AsyncParameterClient(node, target)
    if not client.wait_for_services(timeout_sec=WAIT):
        return {"error": f"{target}'s parameter services did not appear"}
    calls = {"list": lambda: client.list_parameters(), "get": lambda: client.get_parameters(["use_sim_time"]),
             "set": lambda: client.set_parameters([Parameter("use_sim_time", value=False)]),
             "after_set": lambda: client.get_parameters(["use_sim_time"])}
    out = {}
    for label, send in calls.items():
        future = send()
        rclpy.spin_until_future_complete(node, future, timeout_sec=WAIT)
        out[label] = _plain(future.result()) if future.done() else {"error": "no reply"}
    return out


def main() -> None:
    with open(sys.argv[1]) as file:
        plan = json.load(file)
    rclpy.init()
    node = rclpy.create_node("sim_client")
    clients: dict = {}
    out = {}
    for label, service, fields in plan:
        if service == "publish":
            out[label] = publish(node, **fields)
        elif service == "parameters":
            out[label] = parameters(node, fields["node"])
        elif service == "simulate_steps":
            out[label] = simulate_steps(node, fields["steps"])
        else:
            out[label] = call(node, clients, service, fields)
    from rclpy.utilities import get_rmw_implementation_identifier

    out["rmw"] = get_rmw_implementation_identifier()
    node.destroy_node()
    rclpy.shutdown()
    print(json.dumps(out))


if __name__ == "__main__":
    main()
