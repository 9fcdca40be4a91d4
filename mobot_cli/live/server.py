"""The live world's server: one thread steps the World and answers requests between steps.

Between two physics steps the server answers requests for a bounded time (until the next
step is due in real time, a short slice in --fast), so neither a flood of requests nor a
slow or vanished client stops the clock: a ROUTER socket never blocks on send, and a reply
to a peer that is gone is dropped. Robot descriptions load in loader processes (loader.py),
within time and memory limits; the robot is spawned (placed and collision-checked) between
steps, and only then is the spawn answered. A TCP endpoint only serves CURVE-authenticated
clients (keys.py); nothing a client sends ends the loop (every request gets a reply or is dropped).
"""

from __future__ import annotations

import math
import os
import signal
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Sequence

import zmq

from mobot_cli import __version__
from mobot_cli.errors import MobotError, SimulationFault
from mobot_cli.live import endpoint as endpoints
from mobot_cli.live import protocol, schema, spawning
from mobot_cli.live.clock import Clock, pace_text
from mobot_cli.live.loader import Job, Limits, LoaderPool
from mobot_cli.live.lockstep import Lockstep, LockstepRequests, Owed
from mobot_cli.live.protocol import Refusal, Result
from mobot_cli.live.session import Session
from mobot_cli.plan import Plan
from mobot_cli.record.summary import LiveInfo, Status
from mobot_cli.sim.engine import world_for
from mobot_cli.timeline.loop import Attachment, Timeline

# In --fast mode requests get at most as much wall time between two steps as the last step
# took (so a flood of requests at least halves, never stops, the world), within these bounds.
FAST_SLICE = (0.0001, 0.002)  # s
# A --fast world takes a step every few tens of microseconds; looking at the loader processes
# that often would cost it a good part of its pace, so it looks once per this many seconds.
LOADER_CHECK = 0.0005
HOLD_POLL = 20  # ms: how long a paused world waits for a request before it looks at the view's buttons


@dataclass(frozen=True)
class Served:
    """How a live world ended: its status, the steps it took and the requests it answered."""

    status: Status
    error: str | None
    steps: int
    requests: dict[str, int]


class LiveServer:
    """Serve ``plan``'s world; its robots, command scripts and events play as in `mobot run`."""

    def __init__(self, plan: Plan, endpoint: str, *, rtf: float | None = 1.0, bind_any: bool = False,
                 out_dir: Path | None = None, resolved_yaml: str = "", stop_after: int | None = None,
                 attachments: Sequence[Attachment] = (), watch: Callable[[Timeline], None] | None = None,
                 paused: bool = False, limits: Limits = Limits()):
        self.plan, self.rtf, self.stop_after = plan, rtf, stop_after
        self.attachments = attachments  # ride along the timeline (the ROS 2 bridge): timeline/loop.py
        # watch: called with the timeline before the first spawn (a view attaches there).
        self.watch = watch
        self.control = Lockstep(paused)  # pause, resume, step: the protocol's and the view's buttons
        self.out_dir, self.resolved_yaml = out_dir, resolved_yaml
        self.endpoint = endpoints.check(endpoint, bind_any)
        self.session: Session | None = None  # made once the world is up and listening
        self.stopping = False
        self.status, self.error = Status.OK, None
        self.counts: dict[str, int] = {}
        self._socket: zmq.Socket | None = None
        self._authenticator = None  # CURVE on TCP endpoints
        self._poller, self._poller_fds = None, ()  # the socket and the loaders' pipes, while loads run
        self._loaders_due = 0.0
        self._waits: list[Owed] = []
        self._loader = LoaderPool(limits)
        self._opened: list[Attachment] = []  # open on the timeline; flushed before the world waits
        self._handlers: dict[str, Callable] = {
            "ping": self._ping, "spawn": self._spawn, "delete": self._delete, "cmd": self._cmd, "stop": self._stop,
            "goto": self._goto, "list": lambda envelope, request: self.session.listing(request.id),
            "odom": lambda envelope, request: self.session.odometry(request.id, request.name),
            "scan": lambda envelope, request: self.session.scan(request.id, request.name, request.sensor),
            "spawn_mover": self._spawn_mover, "delete_mover": self._delete_mover,
            **LockstepRequests(self).handlers()}

    def serve(self, ready: Callable[[str], None] | None = None) -> Served:
        """Run until `stop`, SIGINT/SIGTERM or ``stop_after`` steps; returns status and counts."""
        restore = _catch_signals(self)
        try:
            with world_for(self.plan) as world:
                self._bind()
                self._loader.start()
                self.session = Session(self.plan, world, self.out_dir, self.resolved_yaml)
                if self.watch is not None:
                    self.watch(self.session.timeline)
                opened = self._opened
                try:
                    for attachment in self.attachments:
                        attachment.open(self.session.timeline)
                        opened.append(attachment)
                    self.session.start()
                    if ready:
                        ready(self.endpoint)
                    self._loop(self.session, Clock(self.plan.physics.dt, self.rtf))
                except BaseException as exc:  # the record must not say "ok" for a world that broke
                    if self.status == Status.OK:
                        interrupted = isinstance(exc, KeyboardInterrupt)
                        self.status = Status.INTERRUPTED if interrupted else Status.FAULT
                        self.error = None if interrupted else str(exc) or repr(exc)
                    raise
                finally:
                    self.answer_owed()
                    try:
                        self.session.close(self.status, self.error, LiveInfo(
                            endpoint=self.endpoint, pace=pace_text(self.rtf), requests=self.counts))
                    finally:
                        for attachment in opened:
                            attachment.close()
        finally:
            self._shutdown()
            restore()
        return Served(self.status, self.error, self._step(), dict(self.counts))

    def _loop(self, session: Session, clock: Clock) -> None:
        timeline, control = session.timeline, self.control
        step_time = 0.0
        while not self.stopping:
            step = timeline.step
            timeline.tick()
            if self._waits:
                self._answer_waits(step)
            # A paused world is not paced: the steps it was asked for go as fast as they can,
            # requests between them, and it waits for the next request in _held.
            self._serve_requests(None if control.paused else clock.due(), step_time)
            if self.stopping or (self.stop_after is not None and step >= self.stop_after):
                break
            if control.hold():
                self._held()
                clock.restart()
                if self.stopping:
                    break
            lockstep_step = control.spend()
            started = time.perf_counter()
            try:
                timeline.advance()
            except SimulationFault as exc:
                if not session.fault(exc):
                    self.status, self.error, self.stopping = Status.FAULT, str(exc), True
            step_time = time.perf_counter() - started
            clock.stepped()
            if lockstep_step:  # real time goes on from here once the world plays again
                clock.restart()

    def _flush(self) -> None:
        for attachment in self._opened:
            attachment.flush()

    def _held(self) -> None:
        """Paused: answer requests (spawns too) until a step is asked for or the world plays; what the
        attachments hold back goes out first (ROS nodes see every step taken)."""
        self._flush()
        while not self.stopping and self.control.hold():
            self._finish_spawns()
            if self._wait(HOLD_POLL):
                self._receive_one()

    # -- the socket -------------------------------------------------------------------------

    def _bind(self) -> None:
        self._socket, self._authenticator, self.endpoint = endpoints.bind(self.endpoint, _server_pid)

    def _serve_requests(self, due: float | None, step_time: float) -> None:
        """Answer requests until the next step is due (real time) or for one slice (fast)."""
        fast = due is None
        end = time.monotonic() + min(max(step_time, FAST_SLICE[0]), FAST_SLICE[1]) if fast else due
        while not self.stopping:
            wait_ms = 0 if fast else max(0, math.ceil((end - time.monotonic()) * 1000))
            if self._wait(wait_ms):
                self._receive_one()
            elif fast:
                return
            if time.monotonic() >= end:
                return

    def _wait(self, wait_ms: int) -> bool:
        """Wait up to ``wait_ms`` for a request; True when one is there.

        While loads run, their processes wake the wait too: a finished (or timed-out) load is
        placed and answered at once, between the same two steps.
        """
        if wait_ms == 0 and time.monotonic() < self._loaders_due:  # --fast: look at loaders each ms only
            return bool(self._socket.poll(0))
        self._loaders_due = time.monotonic() + LOADER_CHECK
        loaders = self._loader.fds() if self._loader.busy else ()
        if not loaders:
            return bool(self._socket.poll(wait_ms))
        if loaders != self._poller_fds:  # a poller per set of loaders: --fast waits once per step
            self._poller, self._poller_fds = zmq.Poller(), loaders
            self._poller.register(self._socket, zmq.POLLIN)
            for fd in loaders:
                self._poller.register(fd, zmq.POLLIN)
        deadline = self._loader.next_deadline()
        if deadline is not None:  # wake up to stop a load that ran out of time
            wait_ms = min(wait_ms, max(0, math.ceil((deadline - time.monotonic()) * 1000)))
        events = dict(self._poller.poll(wait_ms))
        if len(events) > (self._socket in events) or (deadline is not None and time.monotonic() >= deadline):
            self._finish_spawns()
        return self._socket in events

    def _receive_one(self) -> None:
        try:
            frames = self._socket.recv_multipart(zmq.NOBLOCK)
        except zmq.ZMQError:
            return  # the message went away (EAGAIN): nothing to answer
        self._receive(frames)

    def _receive(self, frames: list[bytes]) -> None:
        # REQ peers (and our DEALER client) put an empty delimiter after the identity.
        cut = 2 if len(frames) >= 3 and frames[1] == b"" else 1
        envelope, body = frames[:cut], frames[cut:]
        request_id, op, name = None, None, None
        try:
            if len(body) != 1:
                raise Refusal(Result.INVALID_REQUEST, f"a request is one JSON frame, got {len(body)}")
            document = protocol.decode(body[0])
            request_id, op, name = document.get("id"), document.get("op"), document.get("name")
            request = schema.parse(document)
            self.counts[request.op] = self.counts.get(request.op, 0) + 1
            answer = self._handlers[request.op](envelope, request)
        except Refusal as exc:
            answer = protocol.reply(request_id, exc.result, exc.message)
            if op in ("spawn", "delete", "cmd", "set_state", "reset"):  # the history keeps what was refused, too
                self.history(op=op, name=name, result=exc.result.name, message=exc.message)
        except Exception as exc:  # noqa: BLE001 - a bug must cost one request, never the world
            answer = protocol.reply(request_id, Result.OPERATION_FAILED, f"internal error: {exc!r}"[:500])
        if answer is not None:
            self._send(envelope, answer)

    def _send(self, envelope: list[bytes], answer: dict[str, Any]) -> None:
        payload = protocol.encode_reply(answer)  # never raises: OPERATION_FAILED when it cannot encode
        try:
            self._socket.send_multipart([*envelope, payload], zmq.NOBLOCK)
        except zmq.ZMQError:
            pass  # the peer is gone or not reading: its reply is dropped, the world goes on

    def owe(self, owed: Owed) -> None:
        """Send ``owed``'s answer once the world reaches its step."""
        self._waits.append(owed)

    def history(self, **record: Any) -> None:
        """A line in history.jsonl (when recording); a full disk costs the line, not the world."""
        try:
            self.session.history(**record)
        except (OSError, ValueError):
            pass  # a full disk costs the history line, not the world

    # -- requests ---------------------------------------------------------------------------

    def _ping(self, envelope, request) -> dict[str, Any]:
        step = self._step()
        return protocol.reply(request.id, **self.control.fields(), world=self.plan.world.name,
                              scenario=self.plan.name, step=step,
                              t=step / self.plan.physics.rate_hz, robots=len(self.session.robots),
                              rate_hz=self.plan.physics.rate_hz, pace=pace_text(self.rtf), rtf=self.rtf,
                              pid=os.getpid(),
                              endpoint=self.endpoint, protocol=protocol.PROTOCOL_VERSION, version=__version__)

    def _delete(self, envelope, request) -> dict[str, Any]:
        self.session.remove(request.name)
        return protocol.reply(request.id, name=request.name, step=self._step(), t=self._t())

    def _spawn_mover(self, envelope, request: schema.SpawnMover) -> dict[str, Any]:
        self.session.add_mover(request.mover)
        return protocol.reply(request.id, name=request.mover.name, step=self._step(), t=self._t())

    def _delete_mover(self, envelope, request: schema.DeleteMover) -> dict[str, Any]:
        self.session.remove_mover(request.name)
        return protocol.reply(request.id, name=request.name, step=self._step(), t=self._t())

    def _cmd(self, envelope, request: schema.Cmd) -> dict[str, Any] | None:
        until = self.session.command(request)
        if until is not None and request.wait:
            self.owe(Owed(envelope, request, until, lambda: self._cmd_ended(request)))
            return None
        return protocol.reply(request.id, name=request.name, step=self._step(), t=self._t(), until_step=until)

    def _goto(self, envelope, request: schema.Goto) -> dict[str, Any] | None:
        """Start a goal; with ``wait`` the reply comes when it ends (reached, blocked, ...)."""
        done = (lambda answer: self._send(envelope, answer)) if request.wait else None
        answer = self.session.goto(request, done)
        return None if request.wait else answer

    def _cmd_ended(self, request: schema.Cmd) -> dict[str, Any]:
        try:
            return self.session.odometry(request.id, request.name)
        except Refusal:
            return protocol.reply(request.id, Result.NOT_FOUND,
                                  f"robot '{request.name}' was deleted before its command ended")

    def _stop(self, envelope, request) -> dict[str, Any]:
        self.stopping = True
        return protocol.reply(request.id, step=self._step(), t=self._t(), message="stopping")

    def _spawn(self, envelope, request: schema.Spawn) -> None:
        # Cheap refusals before loading; the same checks run again when the robot is placed.
        if not request.allow_renaming:
            spawning.final_name(request, self.session.taken())
        self.session.reference(request.reference_frame)
        robots = len(self.session.robots) + self._loader.pending
        if robots >= self._loader.limits.robots:
            raise Refusal(Result.LIMIT_EXCEEDED, f"the world has {robots} robot(s), spawned or being "
                          f"loaded; it takes at most {self._loader.limits.robots} (`mobot serve --max-robots`)")
        self._loader.submit(Job(request, self.plan.physics.rate_hz, owner=envelope))
        self._finish_spawns()  # a load refused at once (no loader can start) is answered now
        return None

    # -- replies owed -----------------------------------------------------------------------

    def _finish_spawns(self) -> None:
        """Place the robots whose loads finished (in the order they finished) and answer them."""
        for job in self._loader.poll() if self._loader.busy else ():
            request = job.request
            try:
                if isinstance(job.outcome, Refusal):
                    raise job.outcome
                answer = self.session.place(request, *job.outcome)
            except Refusal as exc:
                answer = protocol.reply(request.id, exc.result, exc.message)
            except MobotError as exc:
                answer = protocol.reply(request.id, spawning.classify(exc), str(exc))
            except Exception as exc:  # noqa: BLE001 - a bug must cost one spawn, never the world
                answer = protocol.reply(request.id, Result.OPERATION_FAILED, f"internal error: {exc!r}")
            if not answer["ok"]:
                self.history(op="spawn", name=request.name, result=answer["result"], message=answer["message"])
            self._send(job.owner, answer)

    def _answer_waits(self, step: int) -> None:
        due = [w for w in self._waits if step >= w.until]
        if due:
            self._flush()  # a step's reply comes after every message of that step is out
        for wait in due:
            self._waits.remove(wait)
            try:
                answer = wait.answer()
            except Exception as exc:  # noqa: BLE001 - a bug must cost one reply, never the world
                answer = protocol.reply(wait.request.id, Result.OPERATION_FAILED, f"internal error: {exc!r}"[:500])
            self._send(wait.envelope, answer)

    def _step(self) -> int:
        return self.session.step if self.session is not None else 0

    def _t(self) -> float:
        return self._step() / self.plan.physics.rate_hz

    def now(self) -> dict[str, Any]:
        """The step and time as reply fields."""
        return {"step": self._step(), "t": self._t()}

    def answer_owed(self, waits_only: bool = False,
                     why: str = "the live world stopped before it could answer") -> None:
        """Every reply still owed (or only those waiting for a step) says why it never came."""
        owed = [] if waits_only else [(job.owner, job.request) for job in self._loader.close()]
        owed += [(wait.envelope, wait.request) for wait in self._waits]
        for envelope, request in owed:
            self._send(envelope, protocol.reply(request.id, Result.INCORRECT_STATE, why))
        self._waits = []

    def _shutdown(self) -> None:
        self._loader.close()
        if self._authenticator is not None:
            self._authenticator.stop()
        if self._socket is not None:
            self._socket.close(linger=0)
            path = endpoints.ipc_path(self.endpoint)
            if path is not None:
                path.unlink(missing_ok=True)


def _server_pid(endpoint: str) -> int | None:
    """The pid of the live world answering at ``endpoint``, or None when nobody answers."""
    from mobot_cli.live.client import Client

    try:
        with Client(endpoint, timeout=1.0) as client:
            return client.ping().get("pid")
    except MobotError:
        return None


def _catch_signals(server: LiveServer) -> Callable[[], None]:
    """SIGINT and SIGTERM stop the loop after the current step, so the record is flushed."""
    if threading.current_thread() is not threading.main_thread():
        return lambda: None

    def stop(signum, frame) -> None:
        server.stopping = True

    old = {sig: signal.signal(sig, stop) for sig in (signal.SIGINT, signal.SIGTERM)}
    return lambda: [signal.signal(sig, handler) for sig, handler in old.items()]
