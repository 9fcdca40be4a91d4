"""Messages appended to rosbags' open MCAP chunk in rosbags' own record layout, many at a time.

rosbags' ``Writer.write`` looks the connection up in a list of dataclasses (one ``==`` per
connection until it matches) and packs each field through its own BytesIO, and its
``close_chunk`` packs two integers per message the same way. ``Records`` keeps exactly the
bookkeeping its McapWriter keeps (the chunk's message index and time span, per-channel counts,
the bag's time span, a chunk closed when it passes 1 MiB) and writes the same bytes, a
sample's messages in one go: the bag is identical byte for byte
(tests/record/test_bag_bytes.py compares the two writers). A log row whose messages all have fixed
shapes is a ``Row``: the records of all its messages, headers included, laid out once
(ros/cdr.py) and packed in one struct call per row.

With a rosbags whose writer does not look as expected, every message goes through
``Writer.write``: slower, the same file.
"""

from __future__ import annotations

import struct
from collections import defaultdict
from io import BytesIO
from itertools import chain
from typing import Sequence

from mobot_cli.ros.cdr import Layout, Source

# A Message record: opcode 0x05, record length, channel id, sequence 0, log time, publish time.
_MESSAGE = struct.Struct("<BQHIQQ")
_HEAD = _MESSAGE.size - 9  # record length before the data: channel, sequence and the two times
_RECORD_HEAD = struct.Struct("<BQHI")  # a Message record up to its times
CHUNK_LIMIT = 2**20  # rosbags' McapWriter closes a chunk once it is past this many bytes


class Row:
    """Messages of fixed shapes logged together, as their MCAP Message records end to end."""

    def __init__(self) -> None:
        self._layout = Layout(encapsulation=b"")
        self.index: list[tuple[int, int]] = []  # (channel id, the record's offset in the row)
        self.cids: list[int] = []  # the channel of each message, in order
        self.spans: list[tuple[object, int, int]] = []  # (connection, where its data starts, ends)
        self.pack = None  # values -> the row's bytes, once built

    def add(self, connection, message: Layout, sources: Sequence[Source]) -> "Row":
        """One more message, its variables drawn from the row's values (``Layout.include``); the
        record's log and publish time are value 0."""
        cid, length = connection.id, message.head + message.size
        self.index.append((cid, self._layout.size))
        self.cids.append(cid)
        self._layout.raw(_RECORD_HEAD.pack(0x05, _HEAD + length, cid, 0)).ref("Q", 0).ref("Q", 0)
        self.spans.append((connection, self._layout.size, self._layout.size + length))
        self._layout.include(message, sources)
        return self

    def build(self) -> "Row":
        """Lay the row out: ``pack(values)`` gives its bytes from then on."""
        self.pack = self._layout.build().pack
        return self

    def messages(self, data: bytes) -> list[tuple[object, bytes]]:
        """The (connection, data) pairs of packed row bytes, as ``Records.write`` takes them."""
        return [(connection, data[start:end]) for connection, start, end in self.spans]


class Records:
    """Writes (connection, data) pairs that share a log time into ``writer``'s open bag."""

    def __init__(self, writer, direct: bool = True):
        self.writer = writer
        storage = writer.storage
        self.direct = direct and all(hasattr(storage, name) for name in (
            "chunk", "close_chunk", "channel_stats", "message_start_time", "message_end_time")) and \
            all(hasattr(storage.chunk, name) for name in ("bio", "msgs", "message_start_time", "message_end_time")) \
            and hasattr(writer, "counts") and hasattr(writer, "min_timestamp")
        # Rows written whose index entries, counts and times are not yet kept (``_settle``, before
        # the next single message and when the chunk closes; a bag closes its chunk before its end).
        self.rows: list[tuple[int, int, Row]] = []  # (log time, offset in the chunk, row)

    def write(self, timestamp: int, messages: Sequence[tuple[object, bytes]]) -> None:
        """Record ``messages``, in order, all logged (and published) at ``timestamp`` ns."""
        if not messages:
            return
        if not self.direct:
            for connection, data in messages:
                self.writer.write(connection, timestamp, data)
            return
        self._settle()
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

    def write_row(self, timestamp: int, row: Row, values: Sequence[float]) -> None:
        """Record a row's messages, logged at ``timestamp`` ns (also ``values[0]``)."""
        data = row.pack(values)
        bio = self.writer.storage.chunk.bio if self.direct else None
        if bio is None or bio.tell() + len(data) > CHUNK_LIMIT:
            # A chunk closes within the row (or rosbags writes it): one message at a time.
            self.write(timestamp, row.messages(data))
            return
        # Its index entries, counts and times wait for the next single message or the chunk's
        # end (``_settle``): a few list appends per row instead of a dozen updates.
        self.rows.append((timestamp, bio.tell(), row))
        bio.write(data)

    def _settle(self) -> None:
        """The bookkeeping of the rows written since the last time, as rosbags' write keeps it."""
        rows = self.rows
        if not rows:
            return
        writer, storage = self.writer, self.writer.storage
        chunk, index = storage.chunk, storage.chunk.msgs
        per_row: dict[Row, int] = {}
        for timestamp, at, row in rows:
            for cid, offset in row.index:
                index[cid].append((timestamp, at + offset))
            per_row[row] = per_row.get(row, 0) + 1
        stats, counts = storage.channel_stats, writer.counts
        for row, n in per_row.items():
            for cid in row.cids:
                stats[cid] += n
                counts[cid] += n
        first, last = min(r[0] for r in rows), max(r[0] for r in rows)
        chunk.message_start_time = min(first, chunk.message_start_time)
        chunk.message_end_time = max(last, chunk.message_end_time)
        storage.message_start_time = min(first, storage.message_start_time)
        storage.message_end_time = max(last, storage.message_end_time)
        writer.min_timestamp = min(first, writer.min_timestamp)
        writer.max_timestamp = max(last, writer.max_timestamp)
        rows.clear()

    def close_chunk(self) -> None:
        """Close the open chunk as rosbags' McapWriter.close_chunk does, its message indexes
        packed in one call per channel instead of two calls per message."""
        storage = self.writer.storage
        if self.direct:
            self._settle()
        if not self.direct or not hasattr(storage, "compressor") or not hasattr(storage, "chunks"):
            storage.close_chunk()
            return
        chunk, bio = storage.chunk, storage.bio
        data = chunk.bio.getvalue()
        # A new zstd context per chunk, as rosbags' compressor makes: a context kept for every
        # chunk runs a fifth fewer instructions but is slower in a run (measured, 1 and 10
        # robots), its tables cold after the physics steps between chunks.
        compressed = storage.compressor(data)
        compression = storage.compression.encode()
        start, end = chunk.message_start_time, chunk.message_end_time
        # The chunk and its message indexes reach the file in one write (one system call).
        parts = [_record(0x06, b"".join((struct.pack("<QQQII", start, end, len(data), 0, len(compression)),
                                         compression, struct.pack("<Q", len(compressed)), compressed)))]
        chunk_start = bio.tell()
        chunk_end = at = chunk_start + len(parts[0])
        offsets = []
        for cid, messages in chunk.msgs.items():
            offsets.append((cid, at))
            parts.append(_record(0x07, struct.pack(f"<HI{2 * len(messages)}Q", cid, 16 * len(messages),
                                                   *chain.from_iterable(messages))))
            at += len(parts[-1])
        bio.write(b"".join(parts))
        index = BytesIO()  # the summary's chunk index, which rosbags writes when it closes
        index.write(struct.pack("<QQQQI", start, end, chunk_start, chunk_end - chunk_start, 10 * len(offsets)))
        index.write(struct.pack("<" + "HQ" * len(offsets), *(value for pair in offsets for value in pair)))
        index.write(struct.pack("<QI", at - chunk_end, len(compression)))
        index.write(compression)
        index.write(struct.pack("<QQ", len(compressed), len(data)))
        storage.chunks.append(index)
        storage.chunk = type(chunk)(2**63 - 1, 0, BytesIO(), defaultdict(list))


def _record(opcode: int, body: bytes) -> bytes:
    """An MCAP record: opcode, length, body."""
    return struct.pack("<BQ", opcode, len(body)) + body
