"""The bag's connections and ``metadata.yaml`` as rosbags' Writer makes them, without its YAML.

rosbags' ``Writer`` dumps every stored QoS profile and, when the bag closes, its metadata twice
(metadata.yaml and the copy inside the MCAP file) through ruamel.yaml, which is slow: most of
what the bag costs besides its messages. The documents are always the same shape
(block mappings with sorted keys, a few kinds of scalars), so they are written here as ruamel
writes them: the same bytes (tests/record/test_bag_bytes.py compares them with rosbags' own).

Anything this module was not written for (another metadata version or storage, a custom QoS, a
topic name that is not a plain YAML word) goes through rosbags' own methods: slower, the same
file.
"""

from __future__ import annotations

import re
from collections.abc import Sequence

WIDTH = 80  # ruamel's line width: a plain value that would pass it starts on the next line
_PLAIN = re.compile(r"/[A-Za-z0-9_/]*\Z|[A-Za-z][A-Za-z0-9_/.]*\Z")  # a word YAML reads back as text
_NOT_TEXT = re.compile(r"(true|false|yes|no|on|off|null|y|n|~|[-+]?[0-9._]+([eE][-+]?[0-9]+)?)\Z", re.I)

# The one QoS profile mobot stores (reliable, transient local, keep last 1: _latched_qos in
# latched_qos) as rosbags' dump_qos_v8 writes it, and that text as a value in the metadata
# documents, which ruamel folds by its column: at the indent of metadata.yaml's key (6) and of
# the MCAP file's copy (4).
LATCHED_QOS = ("- avoid_ros_namespace_conventions: false\n  deadline: {nsec: 0, sec: 0}\n  depth: 1\n"
               "  durability: 1\n  history: 1\n  lifespan: {nsec: 0, sec: 0}\n  liveliness: 1\n"
               "  liveliness_lease_duration: {nsec: 0, sec: 0}\n  reliability: 1")
_LATCHED_VALUE = {
    6: ['"- avoid_ros_namespace_conventions: false\\n  deadline:',
        '        {nsec: 0, sec: 0}\\n  depth: 1\\n  durability: 1\\n  history: 1\\n  lifespan:',
        '        {nsec: 0, sec: 0}\\n  liveliness: 1\\n  liveliness_lease_duration: {nsec: 0,',
        '        sec: 0}\\n  reliability: 1"'],
    4: ['"- avoid_ros_namespace_conventions: false\\n  deadline: {nsec:',
        '      0, sec: 0}\\n  depth: 1\\n  durability: 1\\n  history: 1\\n  lifespan: {nsec: 0,',
        '      sec: 0}\\n  liveliness: 1\\n  liveliness_lease_duration: {nsec: 0, sec: 0}\\n \\',
        '      \\ reliability: 1"'],
}


class _Unknown(Exception):
    """A value this module does not know how ruamel writes: rosbags writes the document."""


def latched_qos() -> list:
    """Reliable, transient local, depth 1: how tf_static and robot_description are published.

    ``ros2 bag play`` offers what the bag says, and rviz subscribes to these two transient
    local; without it they would never connect. Other topics record no QoS, so the player uses
    its reliable, volatile default.
    """
    from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime

    zero = QosTime(0, 0)
    return [Qos(QosHistory.KEEP_LAST, 1, QosReliability.RELIABLE, QosDurability.TRANSIENT_LOCAL,
                zero, zero, QosLiveliness.AUTOMATIC, zero, False)]


def latched_qos_text(profiles: Sequence) -> str | None:
    """rosbags' dump_qos_v8 text of ``profiles`` when it is '' or mobot's latched profile, else None."""
    if not profiles:
        return ""
    return LATCHED_QOS if list(profiles) == latched_qos() else None


def add_connection(writer, topic: str, msgtype: str, msgdef: str, rihs01: str, profiles: Sequence = ()):
    """``writer.add_connection(topic, msgtype, msgdef=, rihs01=, offered_qos_profiles=)`` for a
    version 8 MCAP bag, without dumping the QoS profiles through ruamel."""
    from rosbags.interfaces import Connection, ConnectionExtRosbag2, MessageDefinition, MessageDefinitionFormat

    qos = latched_qos_text(profiles)
    if not _known_writer(writer) or qos is None or msgdef.startswith("=" * 80 + "\nIDL: ") or any(
            c.topic == topic and c.msgtype == msgtype for c in writer.connections):
        return writer.add_connection(topic, msgtype, msgdef=msgdef, rihs01=rihs01, offered_qos_profiles=profiles)
    connection = Connection(id=len(writer.connections) + 1, topic=topic, msgtype=msgtype,
                            msgdef=MessageDefinition(MessageDefinitionFormat.MSG, msgdef), digest=rihs01,
                            msgcount=0, ext=ConnectionExtRosbag2(serialization_format="cdr",
                                                                 offered_qos_profiles=list(profiles)),
                            owner=writer)
    if msgtype not in writer.added_types:
        writer.storage.add_msgtype(connection)
        writer.added_types.add(msgtype)
    writer.storage.add_connection(connection, qos)
    writer.connections.append(connection)
    writer.counts[connection.id] = 0
    return connection


def close(writer) -> None:
    """``writer.close()`` for a version 8 MCAP bag with compressed chunks: the MCAP summary and
    footer, then metadata.yaml (through a .tmp file, as rosbags does)."""
    try:
        if not _known_writer(writer) or getattr(writer, "custom_data", None):
            raise _Unknown
        info = _information(writer)
        inner = "\n".join(_mapping(info, 0))
        outer = "\n".join(_mapping({"rosbag2_bagfile_information": info}, 0)) + "\n"
    except _Unknown:
        writer.close()
        return
    writer.storage.close(writer.version, inner)
    writer.storage = None
    tmp = writer.metapath.with_suffix(".yaml.tmp")
    tmp.write_text(outer, "utf8")
    tmp.replace(writer.metapath)


def _known_writer(writer) -> bool:
    """A rosbags Writer as this module knows it: metadata version 8, MCAP storage, compressed chunks."""
    from rosbags.rosbag2 import CompressionMode, StoragePlugin

    return (getattr(writer, "version", None) == 8 and getattr(writer, "storage_plugin", None) == StoragePlugin.MCAP
            and getattr(writer, "compression_mode", None) == CompressionMode.STORAGE
            and all(hasattr(writer, name) for name in ("connections", "counts", "added_types", "metapath",
                                                       "min_timestamp", "max_timestamp"))
            and writer.storage is not None)


def _information(writer) -> dict:
    """The ``rosbag2_bagfile_information`` mapping rosbags' Writer.close builds."""
    name = writer.storage.path.name
    duration = max(0, writer.max_timestamp - writer.min_timestamp)
    start, count = writer.min_timestamp, sum(writer.counts.values())
    topics = []
    for c in writer.connections:
        qos = latched_qos_text(c.ext.offered_qos_profiles)
        if qos is None or c.ext.serialization_format != "cdr":
            raise _Unknown
        topics.append({"topic_metadata": {"name": c.topic, "type": c.msgtype, "serialization_format": "cdr",
                                          "offered_qos_profiles": qos, "type_description_hash": c.digest},
                       "message_count": writer.counts[c.id]})
    return {
        "version": writer.version, "storage_identifier": "mcap", "relative_file_paths": [name],
        "duration": {"nanoseconds": duration}, "starting_time": {"nanoseconds_since_epoch": start},
        "message_count": count, "topics_with_message_count": topics,
        "compression_format": "", "compression_mode": "",
        "files": [{"path": name, "starting_time": {"nanoseconds_since_epoch": start},
                   "duration": {"nanoseconds": duration}, "message_count": count}],
        "custom_data": None, "ros_distro": "rosbags",
    }


def _mapping(mapping: dict, indent: int) -> list[str]:
    """A block mapping's lines, keys sorted, as ruamel's safe dumper with block style writes it."""
    lines = []
    for key in sorted(mapping):
        value, head = mapping[key], " " * indent + key + ":"
        if isinstance(value, dict) and value:
            lines.append(head)
            lines.extend(_mapping(value, indent + 2))
        elif isinstance(value, list) and value:
            lines.append(head)  # ruamel's sequences in a mapping are not indented
            for item in value:
                if isinstance(item, dict) and item:
                    body = _mapping(item, indent + 2)
                    lines.append(" " * indent + "- " + body[0][indent + 2:])
                    lines.extend(body[1:])
                else:
                    lines.append(" " * indent + "- " + _scalar(item))
        elif value == LATCHED_QOS:
            folded = _LATCHED_VALUE.get(indent)
            if folded is None:
                raise _Unknown
            lines.append(head + " " + folded[0])
            lines.extend(folded[1:])
        else:
            text = _scalar(value)
            if isinstance(value, str) and value and len(head) + 1 + len(text) > WIDTH:
                lines.append(head + " ")  # ruamel leaves the space before the break
                lines.append(" " * (indent + 2) + text)
            else:
                lines.append(head + " " + text)
    return lines


def _scalar(value) -> str:
    """A scalar as ruamel writes it, for the kinds the bag's metadata holds."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if value == "":
        return "''"
    if isinstance(value, str) and _PLAIN.match(value) and not _NOT_TEXT.match(value):
        return value
    raise _Unknown
