"""A ROS 2 participant on Cyclone DDS that sends and takes CDR bytes as they are.

mobot already lays out every message as CDR (ros/cdr.py), so nothing is serialized twice:
cyclonedds' ``DataWriter.write`` only hands the bytes its type's ``serialize`` returns to
``ddspy_write``, so this writer hands over mobot's bytes instead; a reader takes bytes the
same way. The topic's type is the IDL struct of ros2/idl.py, which gives the DDS type name
and the XTypes type information cyclonedds needs to make a topic.

QoS follows rmw_cyclonedds' ``create_readwrite_qos``: autodispose off, history, reliability,
durability (transient local with a durability service of the same history), automatic
liveliness, and ``typehash=RIHS01_...;`` in USER_DATA (Jazzy and later read it); one
difference: a reliable write never blocks (max_blocking_time 0, where rmw waits forever), so
a stalled reader can never stop the world's clock.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Callable

from cyclonedds._clayer import ddspy_take, ddspy_write
from cyclonedds.core import Listener
from cyclonedds.domain import Domain, DomainParticipant
from cyclonedds.pub import DataWriter, Publisher
from cyclonedds.qos import Policy, Qos
from cyclonedds.sub import DataReader, Subscriber
from cyclonedds.topic import Topic
from cyclonedds.util import duration

ANY_STATE = 0xFFFF_FFFF  # read/take mask: every sample, view and instance state


@dataclass(frozen=True)
class QosProfile:
    """The ROS 2 QoS settings mobot uses: history depth, reliability and durability."""

    depth: int = 10
    reliable: bool = True
    transient_local: bool = False


DEFAULT = QosProfile()  # rmw_qos_profile_default: reliable, volatile, keep last 10
LATCHED = QosProfile(depth=1, transient_local=True)  # tf_static, robot_description
DISCOVERY = QosProfile(depth=1, transient_local=True)  # ros_discovery_info, as rmw_cyclonedds


def qos(profile: QosProfile, userdata: bytes = b"") -> Qos:
    """The DDS QoS rmw_cyclonedds makes of a ROS profile."""
    history = Policy.History.KeepLast(profile.depth)
    policies = [Policy.WriterDataLifecycle(autodispose=False), history,
                Policy.Reliability.Reliable(max_blocking_time=0) if profile.reliable
                else Policy.Reliability.BestEffort,
                Policy.Liveliness.Automatic(lease_duration=duration(infinite=True))]
    if profile.transient_local:
        policies += [Policy.Durability.TransientLocal,
                     Policy.DurabilityService(cleanup_delay=0, history=history, max_samples=-1,
                                              max_instances=-1, max_samples_per_instance=-1)]
    else:
        policies.append(Policy.Durability.Volatile)
    if userdata:
        policies.append(Policy.Userdata(data=userdata))
    return Qos(*policies)


class Participant:
    """One DDS participant in a ROS 2 domain; its endpoints' GUIDs are what ROS calls gids."""

    def __init__(self, domain_id: int, config: str, enclave: str = "/"):
        self.domain = Domain(domain_id, config)  # kept: the participant lives in this domain
        self.dp = DomainParticipant(domain_id, qos=Qos(Policy.Userdata(data=f"enclave={enclave};".encode())))
        self.publisher = Publisher(self.dp)
        self.subscriber = Subscriber(self.dp)
        self._topics: dict[tuple[str, type], Topic] = {}

    @property
    def gid(self) -> bytes:
        """The participant's GUID (prefix and entity id), 16 bytes."""
        return self.dp.guid.bytes

    def topic(self, dds_topic: str, struct: type) -> Topic:
        """The DDS topic of that name and IDL struct, made once (one name may carry several types)."""
        key = (dds_topic, struct)
        if key not in self._topics:
            self._topics[key] = Topic(self.dp, dds_topic, struct)
        return self._topics[key]

    def writer(self, dds_topic: str, struct: type, profile: QosProfile, userdata: bytes = b"") -> "Writer":
        """A writer of CDR bytes."""
        return Writer(self.publisher, self.topic(dds_topic, struct), qos(profile, userdata))

    def reader(self, dds_topic: str, struct: type, profile: QosProfile, on_data: Callable[[bytes], None],
               userdata: bytes = b"") -> "Reader":
        """A reader that hands each sample's CDR bytes to ``on_data`` on Cyclone's receive thread."""
        return Reader(self.subscriber, self.topic(dds_topic, struct), qos(profile, userdata), on_data)

    def close(self) -> None:
        """Leave the domain: peers see the participant and its endpoints go at once."""
        self._topics.clear()
        _delete(self.dp)
        _delete(self.domain)


class Writer:
    """Writes CDR bytes (encapsulation header included) as one sample, and knows how many
    readers match: a volatile message nobody reads need not even be built."""

    def __init__(self, publisher: Publisher, topic: Topic, dds_qos: Qos):
        self.readers = 0  # matched readers, kept by Cyclone's listener thread
        self.dds = DataWriter(publisher, topic, qos=dds_qos, listener=Listener(on_publication_matched=self._matched))
        self._ref = self.dds._ref  # noqa: SLF001 - the handle ddspy_write takes

    def _matched(self, writer: DataWriter, status) -> None:
        self.readers = status.current_count

    @cached_property
    def gid(self) -> bytes:
        # Asked for every endpoint at every announcement (ros2/publisher.py): a fleet's node has
        # hundreds, and cyclonedds makes a UUID each time; an endpoint's GUID never changes.
        return self.dds.guid.bytes

    def write(self, data: bytes) -> bool:
        """Send one message (CDR bytes, padded to 4 as cyclonedds' own writer pads them); False
        when it was not sent (reliable readers left too much unacknowledged: a write never waits)."""
        if len(data) % 4:
            data += b"\0" * (-len(data) % 4)
        return ddspy_write(self._ref, data) >= 0

    def delete(self) -> None:
        """Remove the writer from the graph."""
        _delete(self.dds)


class Reader:
    """Takes CDR bytes as they arrive."""

    def __init__(self, subscriber: Subscriber, topic: Topic, dds_qos: Qos, on_data: Callable[[bytes], None]):
        self._on_data = on_data
        self.dds = DataReader(subscriber, topic, qos=dds_qos, listener=Listener(on_data_available=self._take))

    @cached_property
    def gid(self) -> bytes:
        return self.dds.guid.bytes

    def _take(self, reader: DataReader) -> None:
        taken = ddspy_take(reader._ref, ANY_STATE, 64)  # noqa: SLF001
        if isinstance(taken, int):
            return
        for data, info in taken:
            if info.valid_data:
                self._on_data(bytes(data))

    def delete(self) -> None:
        """Remove the reader from the graph."""
        _delete(self.dds)


def _delete(entity) -> None:
    """Delete a DDS entity now (cyclonedds deletes one only when it is garbage collected)."""
    entity.__del__()


def ros_topic_userdata(rihs01: str) -> bytes:
    """USER_DATA for a ROS endpoint: its type hash, as rmw_dds_common encodes it."""
    return f"typehash={rihs01};".encode()


