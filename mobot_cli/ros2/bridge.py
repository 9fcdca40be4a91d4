"""The world as a ROS 2 node: `mobot run --ros2`, `mobot serve --ros2` and a scenario's ``ros2:``.

A ``Bridge`` rides along the timeline (an ``Attachment``) and publishes the records on the
world's thread, as they come or, when the world runs faster than real time, a few at a time
(``BATCH_SECONDS``): a message is built only for a topic some reader matches, and a
write never waits for a reader (one that stops acknowledging loses messages, counted as
unsent, instead of stalling the world). ``threaded=True`` hands the records to a thread of
the bridge's own through a queue instead (samples are dropped, and counted, past
``MAX_BACKLOG`` records waiting); bench/bench_ros2.py measures both, and under CPython's GIL
the thread costs the world more than it saves, so it is not the default.
``/cmd_vel`` arrives on Cyclone's receive thread, waits in a deque, and enters the world
through ``Timeline.command`` at the start of the next tick, on the world's thread, as a live
`mobot cmd` does: it holds until the next one, or for ``cmd_vel_timeout`` when one is set.
Any participant on the domain may publish there, so every sample is checked first
(ros2/inputs.py): one that is malformed, not finite or beyond the limits is dropped, counted per
topic in the stats and said once per topic in summary.json's notices.
"""

from __future__ import annotations

import importlib
import os
import queue
import threading
import time
from collections import deque
from dataclasses import dataclass
from typing import Mapping

from mobot_cli.errors import Location, UsageError
from mobot_cli.plan import Plan, Ros2Settings
from mobot_cli.ros2 import inputs, names
from mobot_cli.sim.holonomic import KINDS as HOLONOMIC
from mobot_cli.timeline.loop import Timeline
from mobot_cli.timeline.records import Reading, Record, Sample

# Records wait and are published together at most this long (wall time): a world stepping in
# real time sends every sample as it comes (they are 20 ms apart), a fast one sends a few at a
# time, which costs about half as much as spreading the same work between physics steps.
BATCH_SECONDS = 0.01
MAX_BACKLOG = 200  # records waiting for the bridge's thread before new samples are dropped
_STOP = object()


@dataclass(frozen=True)
class BridgeStats:
    """What the bridge did: messages sent, samples dropped, commands taken, its thread's time."""

    domain_id: int
    node: str
    messages: int
    unsent: int
    dropped_samples: int
    commands: int
    busy_seconds: float  # CPU seconds spent publishing (the thread that did it)
    error: str | None = None
    left_out: tuple[str, ...] = ()  # robots that got no topics, and why
    dropped_input: tuple[tuple[str, int], ...] = ()  # (topic, cmd_vel samples dropped: malformed, NaN, too fast)


class Bridge:
    """Join ROS 2 as node ``settings.node``; checks every setting before touching the network."""

    def __init__(self, plan: Plan, settings: Ros2Settings, env: Mapping[str, str] | None = None,
                 where: Location | None = None, threaded: bool = False):
        env = os.environ if env is None else env
        names.check_node(settings.node, settings.namespace, where)
        robots = [*plan.robots, *(event.spawn for event in plan.events if event.spawn is not None)]
        for robot in robots:
            names.check_namespace(robot.namespace, Location(key=f"robots.{robot.name}.namespace"))
        self.settings, self.rate = settings, plan.physics.rate_hz
        self._world = plan.world  # its grid goes on /map when settings.map
        self.domain_id = names.domain_id(settings.domain_id, env)
        self.config = names.discovery_config(env, settings.ignore_fastdds_type_information)
        self.gid_size = names.gid_size(env)
        try:
            dds = importlib.import_module("mobot_cli.ros2.dds")  # imports cyclonedds, the `ros2` extra
        except ImportError as exc:
            raise UsageError(f"ROS 2 needs the cyclonedds package, which is not installed ({exc})", location=where,
                             hint="Install the extra: pip install 'mobot-cli[ros2]'.") from None
        try:  # joined now, so that a DDS that cannot start fails before any output is made
            self._participant = dds.Participant(self.domain_id, self.config)
        except Exception as exc:  # noqa: BLE001 - cyclonedds raises its own DDSException
            raise UsageError(f"cannot join ROS 2 domain {self.domain_id}: {exc}", location=where,
                             hint="Check CYCLONEDDS_URI and the ROS discovery variables "
                                  "(ROS_AUTOMATIC_DISCOVERY_RANGE, ROS_STATIC_PEERS).") from None
        self._records: queue.SimpleQueue = queue.SimpleQueue()
        self._twists: deque[tuple[str, float, float, float]] = deque()
        self._sideways_said: set[str] = set()  # robots told once that their linear.y is ignored
        self._timeline: Timeline | None = None
        self._thread: threading.Thread | None = None
        self._threaded = threaded
        self._publisher = None  # the RecordPublisher, once open
        self._pending: list[Record] = []  # records waiting for the next batch
        self._published = 0.0  # monotonic time of the last batch
        self._topics = None
        self._dropped = self._commands = 0
        self._drops = inputs.Drops()
        self._busy = 0.0
        self._error: str | None = None
        self.stats: BridgeStats | None = None  # set by close

    # -- the world's thread -------------------------------------------------------------------

    def open(self, timeline: Timeline) -> None:
        """Join the domain, announce the node and start publishing this timeline's records."""
        from mobot_cli.ros2.publisher import RecordPublisher, Topics

        self._topics = Topics(self._participant, self.settings.node, self.settings.namespace, self.gid_size)
        publisher = RecordPublisher(self._topics, self.rate, self._cmd_vel, self.settings.world_frame)
        publisher.arriving.update(timeline.robots)  # robots placed before the bridge opened
        if self.settings.map and self._world is not None:
            from mobot_cli.ros2.map_topic import publish_map

            publish_map(self._topics, self._world)
        self._publisher = publisher
        self._timeline = timeline
        timeline.attach(self)
        timeline.add_input(self._drain)
        if self._threaded:
            self._thread = threading.Thread(target=self._run, args=(publisher,), name="mobot-ros2", daemon=True)
            self._thread.start()

    def __call__(self, record: Record) -> None:
        if isinstance(record, Reading) and self._publisher is not None and self._publisher.wants_image(record):
            record.data.rgb  # noqa: B018 - rendered now, while the world is where the camera saw it
        if not self._threaded:
            self._pending.append(record)
            now = time.monotonic()
            if now - self._published >= BATCH_SECONDS:
                self._publish_pending(now)
            return
        if isinstance(record, Sample) and self._records.qsize() >= MAX_BACKLOG:
            self._dropped += 1
            return
        self._records.put(record)

    def _publish_pending(self, now: float) -> None:
        """Publish the records that waited (on the world's thread); a failure stops publishing
        and is reported when the bridge closes, but never stops the world."""
        started, publisher = time.thread_time(), self._publisher
        try:
            if self._error is None:
                for record in self._pending:
                    publisher(record)
        except Exception as exc:  # noqa: BLE001 - reported by close(); the world goes on
            self._error = f"{type(exc).__name__}: {exc}"
        self._pending.clear()
        self._published = now
        self._busy += time.thread_time() - started

    def flush(self) -> None:
        """Publish the records waiting for the next batch now: a paused world is about to wait, and
        ROS nodes must see every message of the steps taken (not the world one batch behind)."""
        if self._pending:
            self._publish_pending(time.monotonic())

    def _drain(self) -> None:
        """Apply the /cmd_vel messages that arrived since the last tick."""
        twists, timeline = self._twists, self._timeline
        self._drops.say(timeline.notices)
        while twists:
            name, linear, angular, linear_y = twists.popleft()
            if name in timeline.robots:  # it may have left since
                drive = timeline.robots[name].drive
                if linear_y and (drive is None or drive.kind not in HOLONOMIC):
                    linear_y = 0.0
                    if name not in self._sideways_said:
                        self._sideways_said.add(name)
                        timeline.notices.append(inputs.sideways_ignored(name, drive.kind if drive else "no"))
                timeline.command(name, linear, angular, self.settings.cmd_vel_timeout_steps, linear_y)
                self._commands += 1

    def close(self) -> BridgeStats:
        """Publish what is queued, leave the domain and say what was done (also when the bridge
        never opened: the run stopped before it could); closing twice is harmless."""
        if self.stats is not None:
            return self.stats
        if self._pending:
            self._publish_pending(time.monotonic())
        if self._thread is not None:
            self._records.put(_STOP)
            self._thread.join(timeout=10.0)
            self._thread = None
        self._participant.close()
        if self._timeline is not None:  # drops since the last tick: said before summary.json is written
            self._drops.say(self._timeline.notices)
        topics = self._topics
        self.stats = BridgeStats(self.domain_id, self.settings.node, topics.sent if topics else 0,
                                 topics.unsent if topics else 0, self._dropped, self._commands, self._busy,
                                 self._error, tuple(self._publisher.left_out) if self._publisher else (),
                                 tuple(self._drops.by_topic().items()))
        return self.stats

    # -- other threads ------------------------------------------------------------------------

    def _cmd_vel(self, name: str, topic: str, data: bytes) -> None:
        """A /cmd_vel sample for robot ``name`` (Cyclone's receive thread): queued, or dropped and counted."""
        checked = inputs.cmd_vel(data)
        if isinstance(checked, str):
            self._drops.count(topic, checked)
        else:
            self._twists.append((name, *checked))

    def _run(self, publisher) -> None:
        """The bridge's thread: publish records until told to stop."""
        while True:
            record = self._records.get()
            if record is _STOP:
                return
            if self._error is not None:
                continue  # broken: drain the queue so the world never waits
            started = time.thread_time()
            try:
                publisher(record)
            except Exception as exc:  # noqa: BLE001 - reported when the bridge closes; the world goes on
                self._error = f"{type(exc).__name__}: {exc}"
            self._busy += time.thread_time() - started
