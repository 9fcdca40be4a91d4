"""Another DDS participant, in a process of its own, to see what mobot puts on the wire.

It knows nothing of mobot: it reads Cyclone's built-in discovery topics (what `ddsls` shows)
through the C library itself (cyclonedds-python 11.0.1 crashes taking them), takes topics
as cyclonedds IDL structs, and writes /cmd_vel like any ROS 2 node. Run as a script, it prints
one JSON document:

    python3 tests/ros2/dds_peer.py graph SECONDS          every endpoint and participant seen
    python3 tests/ros2/dds_peer.py take TOPIC TYPE SECONDS  the samples of one topic, as dicts
    python3 tests/ros2/dds_peer.py drive TOPIC LINEAR ANGULAR SECONDS [stamped]  publish a Twist (or a
                                                         TwistStamped, as nav2 from Kilted on) at 20 Hz
    python3 tests/ros2/dds_peer.py send TOPIC HEX...     publish each payload's bytes as they are
                                                         (a hostile or broken participant)
"""

from __future__ import annotations

import ctypes as ct
import dataclasses
import json
import os
import sys
import time

PSEUDO = 0x7FFF0000
BUILTIN = {"participant": PSEUDO + 1, "publication": PSEUDO + 3, "subscription": PSEUDO + 4}


class _Endpoint(ct.Structure):
    _fields_ = [("key", ct.c_uint8 * 16), ("participant_key", ct.c_uint8 * 16),
                ("participant_instance_handle", ct.c_uint64), ("topic_name", ct.c_char_p),
                ("type_name", ct.c_char_p), ("qos", ct.c_void_p)]


class _Participant(ct.Structure):
    _fields_ = [("key", ct.c_uint8 * 16), ("qos", ct.c_void_p)]


class _Info(ct.Structure):
    _fields_ = [("sample_state", ct.c_uint), ("view_state", ct.c_uint), ("instance_state", ct.c_uint),
                ("valid_data", ct.c_bool), ("source_timestamp", ct.c_int64), ("instance_handle", ct.c_uint64),
                ("publication_handle", ct.c_uint64), ("disposed_generation_count", ct.c_uint32),
                ("no_writers_generation_count", ct.c_uint32), ("sample_rank", ct.c_uint32),
                ("generation_rank", ct.c_uint32), ("absolute_generation_rank", ct.c_uint32)]


def _lib():
    from cyclonedds.internal import load_cyclonedds

    lib = load_cyclonedds()
    lib.dds_create_reader.restype = ct.c_int32
    lib.dds_create_reader.argtypes = [ct.c_int32, ct.c_int32, ct.c_void_p, ct.c_void_p]
    lib.dds_read.restype = ct.c_int32
    lib.dds_read.argtypes = [ct.c_int32, ct.POINTER(ct.c_void_p), ct.POINTER(_Info), ct.c_size_t, ct.c_uint32]
    lib.dds_qget_userdata.restype = ct.c_bool
    lib.dds_qget_userdata.argtypes = [ct.c_void_p, ct.POINTER(ct.c_void_p), ct.POINTER(ct.c_size_t)]
    lib.dds_qget_durability.argtypes = [ct.c_void_p, ct.POINTER(ct.c_int)]
    lib.dds_qget_reliability.argtypes = [ct.c_void_p, ct.POINTER(ct.c_int), ct.POINTER(ct.c_int64)]
    lib.dds_qget_history.argtypes = [ct.c_void_p, ct.POINTER(ct.c_int), ct.POINTER(ct.c_int32)]
    lib.dds_return_loan.argtypes = [ct.c_int32, ct.POINTER(ct.c_void_p), ct.c_int32]
    return lib


def _userdata(lib, qos) -> str:
    data, size = ct.c_void_p(), ct.c_size_t()
    if not lib.dds_qget_userdata(qos, ct.byref(data), ct.byref(size)) or not size.value:
        return ""
    return ct.string_at(data, size.value).decode(errors="replace")


def _qos(lib, qos) -> dict:
    durability, reliability, blocking, history, depth = ct.c_int(), ct.c_int(), ct.c_int64(), ct.c_int(), ct.c_int32()
    lib.dds_qget_durability(qos, ct.byref(durability))
    lib.dds_qget_reliability(qos, ct.byref(reliability), ct.byref(blocking))
    lib.dds_qget_history(qos, ct.byref(history), ct.byref(depth))
    return {"durability": ["volatile", "transient_local", "transient", "persistent"][durability.value],
            "reliability": ["best_effort", "reliable"][reliability.value],
            "history": ["keep_last", "keep_all"][history.value], "depth": depth.value}


def _read(lib, reader: int, struct, limit: int = 512):
    buffers = (ct.c_void_p * limit)()
    infos = (_Info * limit)()
    n = lib.dds_read(reader, buffers, infos, limit, limit)
    out = [ct.cast(buffers[i], ct.POINTER(struct)).contents for i in range(max(n, 0)) if infos[i].valid_data]
    return out, buffers, n


def graph(seconds: float) -> dict:
    """Endpoints and participants that discovery found within ``seconds``."""
    from cyclonedds.domain import DomainParticipant

    lib = _lib()
    dp = DomainParticipant(int(os.environ.get("ROS_DOMAIN_ID", "0")))
    readers = {kind: lib.dds_create_reader(dp._ref, handle, None, None) for kind, handle in BUILTIN.items()}
    time.sleep(seconds)
    out: dict = {"participants": [], "publications": [], "subscriptions": [], "self": dp.guid.bytes.hex()}
    samples, buffers, n = _read(lib, readers["participant"], _Participant)
    for p in samples:
        out["participants"].append({"guid": bytes(p.key).hex(), "userdata": _userdata(lib, p.qos)})
    lib.dds_return_loan(readers["participant"], buffers, n)
    for kind in ("publication", "subscription"):
        samples, buffers, n = _read(lib, readers[kind], _Endpoint)
        for e in samples:
            out[kind + "s"].append({"guid": bytes(e.key).hex(), "participant": bytes(e.participant_key).hex(),
                                    "topic": e.topic_name.decode(), "type": e.type_name.decode(),
                                    "userdata": _userdata(lib, e.qos), **_qos(lib, e.qos)})
        lib.dds_return_loan(readers[kind], buffers, n)
    return out


def take(topic: str, type_name: str, seconds: float, transient_local: bool = False) -> list:
    """Samples of one topic received within ``seconds`` (read as cyclonedds IDL structs)."""
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.qos import Policy, Qos
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic

    from mobot_cli.ros2 import idl

    dp = DomainParticipant(int(os.environ.get("ROS_DOMAIN_ID", "0")))
    policies = [Policy.Reliability.Reliable(max_blocking_time=0), Policy.History.KeepLast(100)]
    if transient_local:
        policies.append(Policy.Durability.TransientLocal)
    reader = DataReader(dp, Topic(dp, topic, idl.TYPES[type_name]), qos=Qos(*policies))
    end, got = time.monotonic() + seconds, []
    while time.monotonic() < end:
        got.extend(dataclasses.asdict(s) for s in reader.take(100))
        time.sleep(0.02)
    return got


def drive(topic: str, linear: float, angular: float, seconds: float, stamped: bool = False) -> dict:
    """Publish geometry_msgs/Twist (or TwistStamped) on ``topic`` at 20 Hz for ``seconds``, then stop."""
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.topic import Topic

    from mobot_cli.ros2 import idl

    dp = DomainParticipant(int(os.environ.get("ROS_DOMAIN_ID", "0")))
    writer = DataWriter(dp, Topic(dp, topic, idl.TwistStamped if stamped else idl.Twist))
    end, sent = time.monotonic() + seconds, 0
    while time.monotonic() < end:
        twist = idl.Twist(idl.Vector3(linear, 0.0, 0.0), idl.Vector3(0.0, 0.0, angular))
        # a frame name of odd length: the twist's alignment after it is what the bridge must get right
        writer.write(idl.TwistStamped(idl.Header(idl.Time(sent, 5), "base_link_x"), twist) if stamped else twist)
        sent += 1
        time.sleep(0.05)
    return {"sent": sent, "matched": len(writer.get_matched_subscriptions())}


def send(topic: str, payloads: list[bytes], wait: float = 10.0) -> dict:
    """Publish raw CDR ``payloads`` on a Twist ``topic`` once a reader matches, 0.1 s apart."""
    from cyclonedds._clayer import ddspy_write
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.qos import Policy, Qos
    from cyclonedds.topic import Topic

    from mobot_cli.ros2 import idl

    dp = DomainParticipant(int(os.environ.get("ROS_DOMAIN_ID", "0")))
    writer = DataWriter(dp, Topic(dp, topic, idl.Twist), qos=Qos(Policy.Reliability.Reliable(max_blocking_time=10**9)))
    end = time.monotonic() + wait
    while not writer.get_matched_subscriptions() and time.monotonic() < end:
        time.sleep(0.05)
    time.sleep(1.0)  # the reader's side of the match may come later: samples before it are lost
    written = []  # per payload: whether Cyclone took it (it refuses some bytes no Twist can be)
    for data in payloads:
        written.append(ddspy_write(writer._ref, data) >= 0)  # noqa: SLF001 - bytes as they are
        time.sleep(0.1)
    time.sleep(0.5)  # reliable: let the last ones be acknowledged before the participant goes
    return {"written": written, "matched": len(writer.get_matched_subscriptions())}


if __name__ == "__main__":
    verb, args = sys.argv[1], sys.argv[2:]
    if verb == "graph":
        result = graph(float(args[0]))
    elif verb == "take":
        result = take(args[0], args[1], float(args[2]), transient_local=len(args) > 3)
    elif verb == "send":
        result = send(args[0], [bytes.fromhex(h) for h in args[1:]])
    else:
        result = drive(args[0], float(args[1]), float(args[2]), float(args[3]), args[4:] == ["stamped"])
    print(json.dumps(result, default=lambda o: list(o) if isinstance(o, (bytes, bytearray)) else str(o)))
