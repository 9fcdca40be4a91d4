"""``mobot check RUN_DIR --repair``: make the bag of a killed run readable again.

A run that was killed (or whose disk filled) leaves ``bag/bag.mcap`` without its summary and
footer, and no metadata.yaml: readers that seek (``ros2 bag``, rosbags, Foxglove's indexed
reader) see no messages. The repair reads the file front to back, keeps every record that is
whole (schemas, channels, and the messages of every complete chunk; a chunk cut short is
dropped), and writes them again through rosbags' writer, which adds the chunk index, summary,
footer and metadata.yaml exactly as a closed run's bag has them. The new bag replaces the old
one only once it is complete.
"""

from __future__ import annotations

import os
import shutil
import struct
from dataclasses import dataclass, field
from pathlib import Path
from typing import BinaryIO, Iterator

from mobot_cli.ros.definitions import MESSAGES

MAGIC = b"\x89MCAP0\r\n"
_HEAD = struct.Struct("<BQ")  # opcode, record length
_U16, _U32, _U64 = struct.Struct("<H"), struct.Struct("<I"), struct.Struct("<Q")
FOOTER, SCHEMA, CHANNEL, MESSAGE, CHUNK, DATA_END = 0x02, 0x03, 0x04, 0x05, 0x06, 0x0F


@dataclass
class Repaired:
    """What the repaired bag holds."""

    messages: int = 0
    chunks: int = 0  # complete chunks kept
    last_ns: int | None = None  # log time of the last message
    topics: dict[str, int] = field(default_factory=dict)

    def as_dict(self) -> dict:
        return {"messages": self.messages, "chunks": self.chunks, "topics": dict(self.topics),
                "last_t": self.last_ns / 1e9 if self.last_ns is not None else None}


def needs_repair(bag: Path) -> bool:
    """A bag folder with an MCAP file but no metadata.yaml: what a killed run leaves."""
    return bag.is_dir() and not (bag / "metadata.yaml").is_file() and (bag / f"{bag.name}.mcap").is_file()


def repair_bag(bag: Path) -> Repaired:
    """Rewrite ``bag`` (a rosbag2 folder) from the whole records of its MCAP file; OSError when
    the new one cannot be written. The old one stays as it was unless there was something to keep."""
    from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer

    work = bag.parent / f".{bag.name}-repair"
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir()
    try:
        writer = Writer(work / bag.name, version=8, storage_plugin=StoragePlugin.MCAP)
        writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)  # as BagSink writes
        writer.open()
        with (bag / f"{bag.name}.mcap").open("rb") as f:
            repaired = _copy(f, writer)
        if not repaired.messages:  # nothing whole to keep: leave the bag as it is
            writer.abort()
            return repaired
        writer.close()
        bag.rename(work / "old")
        try:
            (work / bag.name).rename(bag)
        except OSError:
            (work / "old").rename(bag)  # the work folder goes next: never with the only bag in it
            raise
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return repaired


def _copy(f: BinaryIO, writer) -> Repaired:
    """Every whole schema, channel and message of ``f``, in file order, into ``writer``."""
    from rosbags.rosbag2.storage_mcap import get_qos

    schemas: dict[int, tuple[str, str]] = {}  # id -> (message type, definition)
    channels: dict[int, tuple[object, str]] = {}  # id -> (rosbags connection, topic)
    out = Repaired()
    for opcode, body in _whole_records(f, out):
        if opcode == SCHEMA:
            sid = _U16.unpack_from(body)[0]
            name, pos = _string(body, 2)
            _, pos = _string(body, pos)
            schemas.setdefault(sid, (name, body[pos + 4:pos + 4 + _U32.unpack_from(body, pos)[0]].decode()))
        elif opcode == CHANNEL:
            cid, sid = struct.unpack_from("<HH", body)
            if cid in channels or sid not in schemas:
                continue
            topic, pos = _string(body, 4)
            _, pos = _string(body, pos)
            msgtype, msgdef = schemas[sid]
            connection = writer.add_connection(topic, msgtype, msgdef=msgdef, rihs01=_type_hash(msgtype),
                                               offered_qos_profiles=get_qos(body[pos + 4:]))
            channels[cid] = (connection, topic)
        elif opcode == MESSAGE:
            cid = _U16.unpack_from(body)[0]
            if cid not in channels:
                continue
            connection, topic = channels[cid]
            log_time = _U64.unpack_from(body, 6)[0]
            writer.write(connection, log_time, body[22:])
            out.messages += 1
            out.topics[topic] = out.topics.get(topic, 0) + 1
            out.last_ns = log_time if out.last_ns is None else max(out.last_ns, log_time)
    return out


def _whole_records(f: BinaryIO, out: Repaired) -> Iterator[tuple[int, bytes]]:
    """(opcode, body) of the data section's whole records, front to back, with the records of
    each complete chunk in its place. Stops at the first record cut short."""
    from rosbags.rosbag2.storage_mcap import DECOMPRESSORS

    if f.read(len(MAGIC)) != MAGIC:
        return
    for opcode, body in _records(f):
        if opcode in (DATA_END, FOOTER):
            return
        if opcode != CHUNK:
            yield opcode, body
            continue
        size = _U64.unpack_from(body, 16)[0]
        compression, pos = _string(body, 28)
        length = _U64.unpack_from(body, pos)[0]
        try:
            inner = DECOMPRESSORS[compression](body[pos + 8:pos + 8 + length], size)
        except Exception:  # noqa: BLE001 - a chunk written but damaged: keep what came before it
            return
        out.chunks += 1
        yield from _records_in(inner)


def _records(f: BinaryIO) -> Iterator[tuple[int, bytes]]:
    """Whole records of a file from its current position."""
    size = os.fstat(f.fileno()).st_size
    while True:
        head = f.read(_HEAD.size)
        if len(head) < _HEAD.size:
            return
        opcode, length = _HEAD.unpack(head)
        if f.tell() + length > size:
            return  # cut short: the end of what the run wrote
        yield opcode, f.read(length)


def _records_in(data: bytes) -> Iterator[tuple[int, bytes]]:
    pos = 0
    while pos + _HEAD.size <= len(data):
        opcode, length = _HEAD.unpack_from(data, pos)
        pos += _HEAD.size
        if pos + length > len(data):
            return
        yield opcode, data[pos:pos + length]
        pos += length


def _string(buf: bytes, pos: int) -> tuple[str, int]:
    n = _U32.unpack_from(buf, pos)[0]
    return buf[pos + 4:pos + 4 + n].decode(), pos + 4 + n


def _type_hash(msgtype: str) -> str:
    """The RIHS01 hash that metadata.yaml records: mobot's own table, else rosbags' typestore."""
    if msgtype in MESSAGES:
        return MESSAGES[msgtype][1]
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.LATEST).hash_rihs01(msgtype)
