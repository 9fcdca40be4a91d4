"""Messages appended to rosbags' open MCAP chunk in rosbags' own record layout, many at a time.

rosbags' ``Writer.write`` looks the connection up in a list of dataclasses (one ``==`` per
connection until it matches) and packs each field through its own BytesIO, and its
``close_chunk`` packs two integers per message the same way. ``Records`` keeps exactly the
bookkeeping its McapWriter keeps (the chunk's message index and time span, per-channel counts,
the bag's time span, a chunk closed when it passes 1 MiB) and writes the same bytes, a
sample's messages in one go: the bag is identical byte for byte
(tests/run/test_bag_bytes.py compares the two writers).

With a rosbags whose writer does not look as expected, every message goes through
``Writer.write``: slower, the same file.
"""

from __future__ import annotations

import struct
from collections import defaultdict
from io import BytesIO
from typing import Sequence

# A Message record: opcode 0x05, record length, channel id, sequence 0, log time, publish time.
_MESSAGE = struct.Struct("<BQHIQQ")
_HEAD = _MESSAGE.size - 9  # record length before the data: channel, sequence and the two times
CHUNK_LIMIT = 2**20  # rosbags' McapWriter closes a chunk once it is past this many bytes


class Records:
    """Writes (connection, data) pairs that share a log time into ``writer``'s open bag."""

    def __init__(self, writer, direct: bool = True):
        self.writer = writer
        storage = writer.storage
        self.direct = direct and all(hasattr(storage, name) for name in (
            "chunk", "close_chunk", "channel_stats", "message_start_time", "message_end_time")) and \
            all(hasattr(storage.chunk, name) for name in ("bio", "msgs", "message_start_time", "message_end_time")) \
            and hasattr(writer, "counts") and hasattr(writer, "min_timestamp")

    def write(self, timestamp: int, messages: Sequence[tuple[object, bytes]]) -> None:
        """Record ``messages``, in order, all logged (and published) at ``timestamp`` ns."""
        if not messages:
            return
        if not self.direct:
            for connection, data in messages:
                self.writer.write(connection, timestamp, data)
            return
        writer, storage = self.writer, self.writer.storage
        stats, counts, pack = storage.channel_stats, writer.counts, _MESSAGE.pack
        chunk = None
        parts: list[bytes] = []
        for connection, data in messages:
            if chunk is None:  # widened only when a message goes in, as rosbags does
                chunk = storage.chunk
                chunk.message_start_time = min(timestamp, chunk.message_start_time)
                chunk.message_end_time = max(timestamp, chunk.message_end_time)
                bio, index, at = chunk.bio, chunk.msgs, chunk.bio.tell()
            cid = connection.id
            index[cid].append((timestamp, at))
            parts.append(pack(0x05, _HEAD + len(data), cid, 0, timestamp, timestamp))
            parts.append(data)
            at += _MESSAGE.size + len(data)
            stats[cid] += 1
            counts[cid] += 1
            if at > CHUNK_LIMIT:  # where rosbags closes it: after this message
                bio.write(b"".join(parts))
                parts.clear()
                self.close_chunk()
                chunk = None
        if parts:
            bio.write(b"".join(parts))
        storage.message_start_time = min(timestamp, storage.message_start_time)
        storage.message_end_time = max(timestamp, storage.message_end_time)
        writer.min_timestamp = min(timestamp, writer.min_timestamp)
        writer.max_timestamp = max(timestamp, writer.max_timestamp)

    def close_chunk(self) -> None:
        """Close the open chunk as rosbags' McapWriter.close_chunk does, its message indexes
        packed in one call per channel instead of two calls per message."""
        storage = self.writer.storage
        if not self.direct or not hasattr(storage, "compressor") or not hasattr(storage, "chunks"):
            storage.close_chunk()
            return
        chunk, bio = storage.chunk, storage.bio
        data = chunk.bio.getvalue()
        compressed = storage.compressor(data)
        compression = storage.compression.encode()
        start, end = chunk.message_start_time, chunk.message_end_time
        chunk_start = bio.tell()
        bio.write(_record(0x06, b"".join((struct.pack("<QQQII", start, end, len(data), 0, len(compression)),
                                          compression, struct.pack("<Q", len(compressed)), compressed))))
        chunk_end = bio.tell()
        offsets = []
        for cid, messages in chunk.msgs.items():
            offsets.append((cid, bio.tell()))
            flat = [value for pair in messages for value in pair]
            bio.write(_record(0x07, struct.pack(f"<HI{len(flat)}Q", cid, 16 * len(messages), *flat)))
        index = BytesIO()  # the summary's chunk index, which rosbags writes when it closes
        index.write(struct.pack("<QQQQI", start, end, chunk_start, chunk_end - chunk_start, 10 * len(offsets)))
        index.write(struct.pack("<" + "HQ" * len(offsets), *(value for pair in offsets for value in pair)))
        index.write(struct.pack("<QI", bio.tell() - chunk_end, len(compression)))
        index.write(compression)
        index.write(struct.pack("<QQ", len(compressed), len(data)))
        storage.chunks.append(index)
        storage.chunk = type(chunk)(2**63 - 1, 0, BytesIO(), defaultdict(list))


def _record(opcode: int, body: bytes) -> bytes:
    """An MCAP record: opcode, length, body."""
    return struct.pack("<BQ", opcode, len(body)) + body
