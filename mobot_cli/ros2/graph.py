"""The ROS graph's view of mobot: ``ros_discovery_info`` (rmw_dds_common's ParticipantEntitiesInfo).

Every ROS 2 participant publishes on the DDS topic ``ros_discovery_info`` (no ``rt/``
prefix) which nodes it holds and the gids of their readers and writers; `ros2 node list`
and `ros2 node info` come from it, and without it a topic shows as made by a bare DDS
application. A gid is the entity's DDS GUID: 16 bytes since Iron, 24 (zero-padded) before.
The writer is reliable, transient local, keep last 1, as in rmw_cyclonedds, so a node that
starts later still gets the last announcement.
"""

from __future__ import annotations

import struct
from typing import Sequence

from mobot_cli.ros.definitions import MESSAGES
from mobot_cli.ros.definitions import PARTICIPANT_ENTITIES_INFO as MSGTYPE

TOPIC = "ros_discovery_info"
RIHS01 = MESSAGES[MSGTYPE][1]  # rmw_dds_common's generated type description (Jazzy 3.1.0, Kilted)


def participant_entities_info(participant: bytes, node_namespace: str, node_name: str,
                              readers: Sequence[bytes], writers: Sequence[bytes], gid_size: int = 16) -> bytes:
    """CDR of a ParticipantEntitiesInfo with one node (encapsulation header included)."""
    out = bytearray(b"\x00\x01\x00\x00")
    out += _gid(participant, gid_size)
    out += struct.pack("<I", 1)  # one node; the payload is 4-aligned from here on
    for text in (node_namespace, node_name):
        data = text.encode() + b"\0"
        out += struct.pack("<I", len(data)) + data
        out += b"\0" * (-len(out) % 4)
    for gids in (readers, writers):
        out += struct.pack("<I", len(gids))
        for gid in gids:
            out += _gid(gid, gid_size)
    return bytes(out)


def _gid(guid: bytes, size: int) -> bytes:
    if len(guid) != 16:
        raise ValueError(f"a DDS GUID has 16 bytes, got {len(guid)}")
    return guid + b"\0" * (size - 16)
