"""ROS 2 CDR messages of a fixed shape, laid out once and then packed with a few struct calls.

A run records thousands of messages whose frame names, joint names and covariances never
change; only stamps, poses and joint values do. rosbags' serializer builds a message object
and walks it for every message; laying the bytes out once and filling in only the numbers
is far cheaper. tests/record/test_bag.py checks every layout byte for byte against rosbags'
own serializer.

Layouts also join end to end (``include``): a bag's log row, every message of it with its MCAP
record header, is one layout packed in one call (ros/mcap_records.py ``Row``), its messages'
variables drawn from one list of values, so a stamp that five messages carry is passed once.
"""

from __future__ import annotations

import struct
from typing import Sequence, Union

ENCAPSULATION = b"\x00\x01\x00\x00"  # CDR, little endian: what rosbag2 stores for 'cdr'
_SIZES = {"i": 4, "I": 4, "f": 4, "d": 8, "Q": 8}
Source = Union[int, float]  # where an included variable comes from: a value's index, or a constant


class Layout:
    """Build a message shape field by field; constants are given now, variables when packing."""

    def __init__(self, encapsulation: bytes = ENCAPSULATION) -> None:
        # Constant bytes (padding included), or (struct code, index of a variable) pairs.
        self._items: list[bytes | tuple[str, int]] = [encapsulation] if encapsulation else []
        self.size = 0  # payload bytes so far: CDR aligns relative to the payload
        self.head = len(encapsulation)  # bytes before the payload
        self._vars = 0

    def _pad(self, size: int) -> None:
        pad = -self.size % size
        if pad:
            self._const(bytes(pad))

    def _const(self, data: bytes) -> None:
        self._items.append(data)
        self.size += len(data)

    def var(self, code: str, count: int = 1) -> "Layout":
        """``count`` variable numbers of one type: 'i' int32, 'I' uint32, 'f' float32, 'd' float64."""
        self._pad(_SIZES[code])
        for _ in range(count):
            self.ref(code, self._vars)
        return self

    def ref(self, code: str, index: int) -> "Layout":
        """A variable number, unaligned, that is value ``index`` when packing (several may share one)."""
        self._items.append((code, index))
        self._vars = max(self._vars, index + 1)
        self.size += _SIZES[code]
        return self

    def raw(self, data: bytes) -> "Layout":
        """Constant bytes, unaligned (an MCAP record header between messages)."""
        self._const(data)
        return self

    def include(self, other: "Layout", sources: Sequence[Source]) -> "Layout":
        """``other``'s bytes next, its i-th variable taken from value ``sources[i]`` (an int), or
        fixed (a float, for a float field); ``other`` aligns relative to its own start, as a
        message's payload does."""
        count, items = other._vars, other._items  # noqa: SLF001 - another Layout: this class's own internals
        if len(sources) != count:
            raise ValueError(f"expected {count} sources, got {len(sources)}")
        for item in items:
            if isinstance(item, bytes):
                self._const(item)
                continue
            code, index = item
            source = sources[index]
            if isinstance(source, int):
                self.ref(code, source)
            else:
                self._const(struct.pack("<" + code, source))
        return self

    def u32(self, value: int) -> "Layout":
        """A constant uint32 (a sequence length)."""
        self._pad(4)
        self._const(struct.pack("<I", value))
        return self

    def string(self, text: str) -> "Layout":
        """A constant string."""
        data = text.encode("utf-8") + b"\0"
        self.u32(len(data))
        self._const(data)
        return self

    def doubles(self, values: Sequence[float]) -> "Layout":
        """Constant float64 values (a fixed-size array such as a covariance)."""
        self._pad(8)
        self._const(struct.pack(f"<{len(values)}d", *values))
        return self

    def strings(self, texts: Sequence[str]) -> "Layout":
        """A constant sequence of strings."""
        self.u32(len(texts))
        for text in texts:
            self.string(text)
        return self

    def header(self, frame_id: str) -> "Layout":
        """std_msgs/Header: variable stamp (sec, nanosec), constant frame_id."""
        return self.var("i").var("I").string(frame_id)

    def build(self) -> "Packer":
        """The finished shape."""
        return Packer(*self._struct())

    def pack(self, values: Sequence[float]) -> bytes:
        """One message of this shape, packed without building a Packer (for a message sent once)."""
        st, args, count = self._struct()
        if len(values) != count:
            raise ValueError(f"expected {count} values, got {len(values)}")
        return st.pack(*(arg if isinstance(arg, bytes) else values[arg] for arg in args))

    def _struct(self) -> tuple[struct.Struct, list[bytes | int], int]:
        fmt, args = ["<"], []  # struct codes, and per argument its constant or its variable's index
        for item in self._items:
            if isinstance(item, tuple):
                fmt.append(item[0])
                args.append(item[1])
            elif args and isinstance(args[-1], bytes):  # constants side by side: one argument
                args[-1] += item
                fmt[-1] = f"{len(args[-1])}s"
            else:
                fmt.append(f"{len(item)}s")
                args.append(item)
        return struct.Struct("".join(fmt)), args, self._vars


class Packer:
    """Packs one message of a fixed shape from its variable numbers, in field order."""

    def __init__(self, st: struct.Struct, args: list[bytes | int], count: int):
        self.count = count
        # One struct call per message: a small function that passes the constants and the
        # variables in field order, made once per shape (as dataclasses make __init__).
        names = {f"c{i}": arg for i, arg in enumerate(args) if isinstance(arg, bytes)}
        call = ", ".join(f"c{i}" if isinstance(arg, bytes) else f"v[{arg}]" for i, arg in enumerate(args))
        scope = {"pack": st.pack, **names}
        self._pack = eval(f"lambda v: pack({call})", scope)  # noqa: S307 - text built above

    def pack(self, values: Sequence[float]) -> bytes:
        """The serialized message (encapsulation header included)."""
        if len(values) != self.count:
            raise ValueError(f"expected {self.count} values, got {len(values)}")
        return self._pack(values)
