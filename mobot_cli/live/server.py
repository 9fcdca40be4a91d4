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
from mobot_cli.errors import MobotError, SimulationFault, UsageError
from mobot_cli.live import endpoint as endpoints
from mobot_cli.live import keys
from mobot_cli.live import protocol, schema, spawning
from mobot_cli.live.clock import Clock, pace_text
from mobot_cli.live.loader import Job, Limits, LoaderPool
from mobot_cli.live.protocol import Refusal, Result
from mobot_cli.live.session import Session
from mobot_cli.run.record import LiveInfo, Status
from mobot_cli.run.timeline import Attachment, Timeline
from mobot_cli.sim.plan import Plan
from mobot_cli.sim.engine import open_world

# In --fast mode requests get at most as much wall time between two steps as the last step
# took (so a flood of requests at least halves, never stops, the world), within these bounds.
FAST_SLICE = (0.0001, 0.002)  # s
# A --fast world takes a step every few tens of microseconds; looking at the loader processes
# that often would cost it a good part of its pace, so it looks once per this many seconds.
LOADER_CHECK = 0.0005
HOLD_POLL = 0.02  # s: how long a held (paused) world waits for requests between two looks at hold()


@dataclass
class _Pending:
    """A reply the server owes: a spawn whose robot is loading, or a `cmd --wait`."""

    envelope: list[bytes]
    request: Any
    until: int | None = None  # cmd: the step at which the command ends


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
                 hold: Callable[[], bool] | None = None,
                 limits: Limits = Limits()):
        self.plan, self.rtf, self.stop_after = plan, rtf, stop_after
        self.attachments = attachments  # ride along the timeline (the ROS 2 bridge): run/timeline.py
        # watch: called with the timeline before the first spawn (a view attaches there);
        # hold: asked before each step, True keeps the world paused while requests are answered.
        self.watch, self.hold = watch, hold
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
        self._waits: list[_Pending] = []
        self._loader = LoaderPool(limits)
        self._handlers: dict[str, Callable] = {
            "ping": self._ping, "list": self._list, "spawn": self._spawn, "delete": self._delete,
            "cmd": self._cmd, "odom": self._odom, "scan": self._scan, "stop": self._stop, "goto": self._goto}

    def serve(self, ready: Callable[[str], None] | None = None) -> Served:
        """Run until `stop`, SIGINT/SIGTERM or ``stop_after`` steps; returns status and counts."""
        restore = _catch_signals(self)
        try:
            with open_world(self.plan.physics, self.plan.world, seed=self.plan.seed) as world:
                self._bind()
                self._loader.start()
                self.session = Session(self.plan, world, self.out_dir, self.resolved_yaml)
                if self.watch is not None:
                    self.watch(self.session.timeline)
                opened: list[Attachment] = []
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
                    self._answer_owed()
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
        timeline = session.timeline
        step_time = 0.0
        while not self.stopping:
            step = timeline.step
            timeline.tick()
            self._answer_waits(step)
            self._serve_requests(clock.due(), step_time)  # finished loads are answered there, too
            if self.stopping or (self.stop_after is not None and step >= self.stop_after):
                break
            if self.hold is not None and self.hold():
                self._held(clock)
                if self.stopping:
                    break
            started = time.perf_counter()
            try:
                timeline.advance()
            except SimulationFault as exc:
                if not session.fault(exc):
                    self.status, self.error, self.stopping = Status.FAULT, str(exc), True
            step_time = time.perf_counter() - started
            clock.stepped()

    def _held(self, clock: Clock) -> None:
        """Paused: answer requests (spawns too) until released, then go on where the clock stopped."""
        since = time.monotonic()
        while not self.stopping and self.hold():
            self._finish_spawns()
            self._serve_requests(time.monotonic() + HOLD_POLL, 0.0)
        clock.start += time.monotonic() - since

    # -- the socket -------------------------------------------------------------------------

    def _bind(self) -> None:
        path = endpoints.ipc_path(self.endpoint)
        if path is not None:
            endpoints.claim_socket_file(self.endpoint, path, _server_pid)
        socket = zmq.Context.instance().socket(zmq.ROUTER)
        socket.setsockopt(zmq.LINGER, 0)
        socket.setsockopt(zmq.MAXMSGSIZE, protocol.HARD_LIMIT_BYTES)  # larger: the peer is dropped
        if path is None:  # TCP: only clients with an authorised key get through the handshake
            try:
                self._authenticator = keys.secure_server(socket)
            except BaseException:
                socket.close()
                raise
        old = os.umask(0o177)  # the socket file is born 0600: no window with looser rights
        try:
            socket.bind(self.endpoint)
        except zmq.ZMQError as exc:
            socket.close()
            raise UsageError(f"cannot listen at {self.endpoint}: {exc}",
                             hint="Pick another --endpoint (is another server using it?).") from None
        finally:
            os.umask(old)
        self._socket = socket
        if path is not None:
            os.chmod(path, 0o600)
        else:  # tcp://127.0.0.1:* picks a free port: report the one it got
            self.endpoint = socket.getsockopt_string(zmq.LAST_ENDPOINT)

    def _serve_requests(self, due: float | None, step_time: float) -> None:
        """Answer requests until the next step is due (real time) or for one slice (fast)."""
        fast = due is None
        end = time.monotonic() + min(max(step_time, FAST_SLICE[0]), FAST_SLICE[1]) if fast else due
        while not self.stopping:
            wait_ms = 0 if fast else max(0, math.ceil((end - time.monotonic()) * 1000))
            if self._wait(wait_ms):
                try:
                    self._receive(self._socket.recv_multipart(zmq.NOBLOCK))
                except zmq.ZMQError:
                    pass  # the message went away (EAGAIN): nothing to answer
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
            if op in ("spawn", "delete", "cmd"):  # the history keeps what was refused, too
                self._history(op=op, name=name, result=exc.result.name, message=exc.message)
        except Exception as exc:  # a bug must cost one request, never the world
            answer = protocol.reply(request_id, Result.OPERATION_FAILED, f"internal error: {exc!r}"[:500])
        if answer is not None:
            self._send(envelope, answer)

    def _send(self, envelope: list[bytes], answer: dict[str, Any]) -> None:
        payload = protocol.encode_reply(answer)  # never raises: OPERATION_FAILED when it cannot encode
        try:
            self._socket.send_multipart([*envelope, payload], zmq.NOBLOCK)
        except zmq.ZMQError:
            pass  # the peer is gone or not reading: its reply is dropped, the world goes on

    def _history(self, **record: Any) -> None:
        try:
            self.session.history(**record)
        except (OSError, ValueError):
            pass  # a full disk costs the history line, not the world

    # -- requests ---------------------------------------------------------------------------

    def _ping(self, envelope, request) -> dict[str, Any]:
        step = self._step()
        return protocol.reply(request.id, world=self.plan.world.name, scenario=self.plan.name, step=step,
                              t=step / self.plan.physics.rate_hz, robots=len(self.session.robots),
                              rate_hz=self.plan.physics.rate_hz, pace=pace_text(self.rtf), rtf=self.rtf,
                              pid=os.getpid(),
                              endpoint=self.endpoint, protocol=protocol.PROTOCOL_VERSION, version=__version__)

    def _list(self, envelope, request) -> dict[str, Any]:
        return self.session.listing(request.id)

    def _odom(self, envelope, request) -> dict[str, Any]:
        return self.session.odometry(request.id, request.name)

    def _scan(self, envelope, request) -> dict[str, Any]:
        return self.session.scan(request.id, request.name, request.sensor)

    def _delete(self, envelope, request) -> dict[str, Any]:
        self.session.remove(request.name)
        return protocol.reply(request.id, name=request.name, step=self._step(), t=self._t())

    def _cmd(self, envelope, request: schema.Cmd) -> dict[str, Any] | None:
        until = self.session.command(request)
        if until is not None and request.wait:
            self._waits.append(_Pending(envelope, request, until=until))
            return None
        return protocol.reply(request.id, name=request.name, step=self._step(), t=self._t(), until_step=until)

    def _goto(self, envelope, request: schema.Goto) -> dict[str, Any] | None:
        """Start a goal; with ``wait`` the reply comes when it ends (reached, blocked, ...)."""
        done = (lambda answer: self._send(envelope, answer)) if request.wait else None
        answer = self.session.goto(request, done)
        return None if request.wait else answer

    def _stop(self, envelope, request) -> dict[str, Any]:
        self.stopping = True
        return protocol.reply(request.id, step=self._step(), t=self._t(), message="stopping")

    def _spawn(self, envelope, request: schema.Spawn) -> None:
        # Cheap refusals before loading; the same checks run again when the robot is placed.
        if not request.allow_renaming:
            spawning.final_name(request, self.session.taken())
        self.session.reference(request)
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
            except Exception as exc:
                answer = protocol.reply(request.id, Result.OPERATION_FAILED, f"internal error: {exc!r}")
            if not answer["ok"]:
                self._history(op="spawn", name=request.name, result=answer["result"], message=answer["message"])
            self._send(job.owner, answer)

    def _answer_waits(self, step: int) -> None:
        for wait in [w for w in self._waits if step >= w.until]:
            self._waits.remove(wait)
            name = wait.request.name
            try:
                answer = self.session.odometry(wait.request.id, name)
            except Refusal:
                answer = protocol.reply(wait.request.id, Result.NOT_FOUND,
                                        f"robot '{name}' was deleted before its command ended")
            self._send(wait.envelope, answer)

    def _step(self) -> int:
        return self.session.step if self.session is not None else 0

    def _t(self) -> float:
        return self._step() / self.plan.physics.rate_hz

    def _answer_owed(self) -> None:
        """Every reply still owed says the world stopped."""
        owed = [(job.owner, job.request) for job in self._loader.close()]
        owed += [(wait.envelope, wait.request) for wait in self._waits]
        for envelope, request in owed:
            self._send(envelope, protocol.reply(request.id, Result.INCORRECT_STATE,
                                                "the live world stopped before it could answer"))
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
