"""The simulation_interfaces services and the SimulateSteps action, on rclpy (`mobot serve --ros2`).

Why rclpy: ROS 2's default middleware is Fast DDS, whose service clients match a reply to their
request by the related-sample-identity that the replier writes as inline QoS; Cyclone DDS's
Python API cannot write it, so a service served over cyclonedds answers Cyclone clients only.
When rclpy and the simulation_interfaces package import (a sourced ROS 2 Jazzy, or the
community ``ros-jazzy-*`` wheels with a simulation_interfaces built from its .srv files:
docs/ros2.md), the world serves these on an rclpy node named as the bridge's node (``/mobot``),
in whatever RMW rclpy uses; that node also answers the parameter services every ROS 2 node has
(``ros2 param get /mobot use_sim_time``: true, every stamp mobot sends is sim time). The topics
stay on the Cyclone bridge (ros2/bridge.py).

Every service is a client of the world's own live endpoint (live/client.py), so what ROS 2 asks
is checked, sandboxed, limited and recorded exactly as `mobot spawn`, `mobot step`, ... are, and
answered between physics steps: the world keeps its pace. Callbacks run on rclpy's executor
threads, one live connection each.
"""

from __future__ import annotations

import threading
from typing import Any, Callable

from mobot_cli.errors import MobotError
from mobot_cli.live.client import Client
from mobot_cli.live.protocol import Refusal, Result
from mobot_cli.ros2 import sim_requests as sr

SPAWN_TIMEOUT = 120.0  # s: a load takes at most `serve --load-timeout` (10 s by default), then placing
STEP_TIMEOUT = 3600.0  # s: a StepSimulation's reply comes when its steps are taken
REQUEST_TIMEOUT = 10.0


def available() -> str | None:
    """None when rclpy and simulation_interfaces import, else why the services are off."""
    try:
        import rclpy  # noqa: F401
    except ImportError as exc:
        return f"rclpy is not importable ({exc})"
    try:
        import simulation_interfaces.srv  # noqa: F401
    except ImportError as exc:
        return f"the simulation_interfaces package is not importable ({exc})"
    return None


def _refuse_changes(parameters):
    """`ros2 param set`: refused; mobot's parameters describe it, they do not configure it."""
    from rcl_interfaces.msg import SetParametersResult

    return SetParametersResult(successful=False, reason="mobot's stamps are always sim time; "
                               "its settings are `mobot serve` options")


class SimulationServices:
    """An rclpy node serving simulation_interfaces for the live world at ``endpoint``."""

    def __init__(self, endpoint: str, node: str, namespace: str, domain_id: int, rate_hz: int):
        import rclpy
        from rclpy.action import ActionServer, CancelResponse
        from rclpy.callback_groups import ReentrantCallbackGroup
        from rclpy.context import Context
        from rclpy.executors import MultiThreadedExecutor
        from simulation_interfaces import action, msg, srv

        self.endpoint, self.rate_hz = endpoint, rate_hz
        self.msg, self.srv, self.action = msg, srv, action
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        from rclpy.parameter import Parameter

        # use_sim_time (every node declares it): true, as mobot's stamps are sim time; rclpy's
        # parameter services answer `ros2 param get/list/set` on this node.
        self.node = rclpy.create_node(node, namespace=namespace, context=self.context,
                                      parameter_overrides=[Parameter("use_sim_time", value=True)])
        self.node.add_on_set_parameters_callback(_refuse_changes)
        group = ReentrantCallbackGroup()
        for name, handler in self._handlers().items():
            kind = getattr(srv, "".join(part.title() for part in name.split("_")))
            self.node.create_service(kind, name, self._wrap(name, handler), callback_group=group)
        self._action = ActionServer(self.node, action.SimulateSteps, "simulate_steps", self._simulate_steps,
                                    cancel_callback=lambda goal: CancelResponse.ACCEPT, callback_group=group)
        self.executor = MultiThreadedExecutor(num_threads=4, context=self.context)
        self.executor.add_node(self.node)
        self._thread = threading.Thread(target=self._spin, name="mobot-ros2-services", daemon=True)
        self._thread.start()

    def _spin(self) -> None:
        try:
            self.executor.spin()
        except Exception:  # noqa: BLE001 - the context was shut down: the world is closing
            pass

    def close(self) -> None:
        """Leave the ROS graph."""
        self.executor.shutdown(timeout_sec=2.0)
        self._action.destroy()
        self.node.destroy_node()
        if self.context.ok():
            self.context.shutdown()
        self._thread.join(timeout=5.0)

    # -- plumbing --------------------------------------------------------------------------------

    def _handlers(self) -> dict[str, Callable[[Any, Any], Any]]:
        return {"get_simulator_features": self._features, "spawn_entity": self._spawn,
                "delete_entity": self._delete, "get_entities": self._entities,
                "get_entity_state": self._entity_state, "get_entities_states": self._entities_states,
                "set_entity_state": self._set_state, "get_simulation_state": self._simulation_state,
                "set_simulation_state": self._set_simulation_state, "step_simulation": self._step,
                "reset_simulation": self._reset, "get_entity_info": self._entity_info,
                "get_entity_bounds": self._entity_bounds, "get_spawnables": self._spawnables}

    def _wrap(self, service: str, handler: Callable[[Any, Any], Any]) -> Callable[[Any, Any], Any]:
        """A service callback: a refusal or any failure becomes the response's Result, never an exception."""
        def callback(request, response):
            try:
                with Client(self.endpoint, timeout=REQUEST_TIMEOUT) as client:
                    reply = handler(client, request, response)
            except Refusal as exc:
                reply = sr.refused(exc.result, exc.message)
            except MobotError as exc:  # the world did not answer (it is stopping)
                reply = sr.refused(Result.OPERATION_FAILED, str(exc))
            except Exception as exc:  # noqa: BLE001 - a bug costs one call, never the world
                reply = sr.refused(Result.OPERATION_FAILED, f"internal error: {exc!r}"[:500])
            if hasattr(response, "result") and reply is not None:
                response.result.result, response.result.error_message = sr.result_code(reply, service)
            return response
        return callback

    def _header(self, header, step: int, frame_id: str) -> None:
        header.stamp.sec, header.stamp.nanosec = sr.stamp(step, self.rate_hz)
        header.frame_id = frame_id

    def _fill_state(self, state, reply: dict[str, Any]) -> None:
        """An EntityState from a live get_state reply (ground truth; acceleration is not simulated: 0)."""
        self._header(state.header, reply["step"], reply.get("reference_frame", "world"))
        pose, twist = reply["pose"], reply["twist"]
        state.pose.position.x, state.pose.position.y, state.pose.position.z = pose["x"], pose["y"], pose["z"]
        o = state.pose.orientation
        o.x, o.y, o.z, o.w = pose["quat"]
        for target, source in ((state.twist.linear, twist["linear"]), (state.twist.angular, twist["angular"])):
            target.x, target.y, target.z = source["x"], source["y"], source["z"]

    # -- the services -------------------------------------------------------------------------------

    def _features(self, client: Client, request, response):
        features = response.features
        features.features = sorted(sr.FEATURES.values())
        features.spawn_formats = list(sr.SPAWN_FORMATS)
        features.custom_info = sr.CUSTOM_INFO
        return None  # GetSimulatorFeatures has no Result

    def _spawn(self, client: Client, request, response):
        reply = client.call("spawn", timeout=SPAWN_TIMEOUT, **sr.spawn(request))
        if reply.get("ok"):
            response.entity_name = reply["name"]
        return reply

    def _delete(self, client: Client, request, response):
        return client.call("delete", name=request.entity)

    def _matching(self, client: Client, filters) -> tuple[dict[str, Any], list[str]]:
        accept = sr.entity_filter(filters)
        reply = client.call("list")
        names = [robot["name"] for robot in reply.get("robots", ())] if reply.get("ok") else []
        return reply, [name for name in names if accept(name)]

    def _entities(self, client: Client, request, response):
        reply, names = self._matching(client, request.filters)
        response.entities = names
        return reply

    def _entity_state(self, client: Client, request, response):
        reply = client.call("get_state", name=request.entity)
        if reply.get("ok"):
            self._fill_state(response.state, reply)
        return reply

    def _entities_states(self, client: Client, request, response):
        """Each matching robot's state; one that leaves between the listing and its state is left out."""
        reply, names = self._matching(client, request.filters)
        entities, states = [], []
        for name in names:
            one = client.call("get_state", name=name)
            if one.get("ok"):
                state = self.msg.EntityState()
                self._fill_state(state, one)
                entities.append(name)
                states.append(state)
        response.entities, response.states = entities, states
        return reply

    def _listed(self, client: Client, entity: str) -> tuple[dict[str, Any], dict[str, Any] | None]:
        """The live listing and the robot named ``entity`` in it (None when the world did not
        answer); a Refusal (NOT_FOUND) when the world holds no such robot."""
        reply = client.call("list")
        if not reply.get("ok"):
            return reply, None
        robot = next((r for r in reply["robots"] if r["name"] == entity), None)
        if robot is None:
            raise Refusal(Result.NOT_FOUND, f"no robot named '{entity}' in the world")
        return reply, robot

    def _entity_info(self, client: Client, request, response):
        """Every entity mobot lists is a robot (CATEGORY_ROBOT), without tags."""
        reply, robot = self._listed(client, request.entity)
        if robot is not None:
            response.info.category.category = self.msg.EntityCategory.CATEGORY_ROBOT
            response.info.description = f"a robot in namespace {robot['namespace']}" + \
                ("" if robot["has_drive"] else " (no drive: it does not take cmd_vel)")
        return reply

    def _entity_bounds(self, client: Client, request, response):
        """TYPE_BOX round the robot's collision geometry in its root link's frame, joints at
        zero: points[0] the upper corner, points[1] the lower one, as Bounds.msg lists them."""
        reply, robot = self._listed(client, request.entity)
        if robot is None:
            return reply
        if robot.get("bounds") is None:
            return sr.refused(Result.OPERATION_FAILED, f"the collision geometry of '{request.entity}' is not known")
        from geometry_msgs.msg import Vector3

        response.bounds.type = sr.BOUNDS_BOX
        response.bounds.points = [Vector3(x=float(x), y=float(y), z=float(z))
                                  for x, y, z in (robot["bounds"]["max"], robot["bounds"]["min"])]
        return reply

    def _spawnables(self, client: Client, request, response):
        found, reply = sr.spawnables(request.sources)
        items = []
        for uri, description in found:
            item = self.msg.Spawnable()
            item.uri, item.description = uri, description  # spawn_bounds: TYPE_EMPTY, none given
            items.append(item)
        response.spawnables = items
        return reply

    def _set_state(self, client: Client, request, response):
        return client.call("set_state", **sr.set_state(request))

    def _simulation_state(self, client: Client, request, response):
        reply = client.call("ping")
        response.state.state = sr.state_code(reply)
        return reply

    def _set_simulation_state(self, client: Client, request, response):
        plan = sr.set_simulation_state(request.state.state, client.call("ping").get("state", "playing"))
        if isinstance(plan, int):
            return sr.refused(plan, "the world is already in that state")
        reply: dict[str, Any] = {}
        for op, fields in plan:
            reply = client.call(op, **fields)
            if not reply.get("ok"):
                break
        return reply

    def _step(self, client: Client, request, response):
        return client.call("step", timeout=STEP_TIMEOUT, steps=int(request.steps), states=False)

    def _reset(self, client: Client, request, response):
        sr.reset_scope(request.scope)
        return client.call("reset")

    def _simulate_steps(self, goal):
        """SimulateSteps: one step at a time, feedback after each; a cancel ends it between steps."""
        total = int(goal.request.steps)
        result = self.action.SimulateSteps.Result()
        feedback = self.action.SimulateSteps.Feedback()
        done, reply = 0, {"ok": True, "code": sr.OK, "message": ""}
        try:
            with Client(self.endpoint, timeout=REQUEST_TIMEOUT) as client:
                if total < 1:
                    reply = sr.refused(Result.OPERATION_FAILED, "SimulateSteps needs steps >= 1")
                while done < total and reply.get("ok"):
                    if goal.is_cancel_requested:
                        break
                    reply = client.call("step", timeout=STEP_TIMEOUT, steps=1, states=False)
                    if reply.get("ok"):
                        done += 1
                        feedback.completed_steps, feedback.remaining_steps = done, total - done
                        goal.publish_feedback(feedback)
        except MobotError as exc:
            reply = sr.refused(Result.OPERATION_FAILED, str(exc))
        result.result.result, result.result.error_message = sr.result_code(reply, "simulate_steps")
        if goal.is_cancel_requested and done < total:
            result.result.error_message = f"cancelled after {done} of {total} step(s)"
            goal.canceled()
        elif reply.get("ok"):
            goal.succeed()
        else:
            goal.abort()
        return result
