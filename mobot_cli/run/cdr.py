"""ROS 2 CDR messages of a fixed shape, laid out once and then packed with a few struct calls.

A run records thousands of messages whose frame names, joint names and covariances never
change; only stamps, poses and joint values do. rosbags' serializer builds a message object
and walks it for every message (~18 us for an Odometry); laying the bytes out once and
filling in the numbers is ~1 us. tests/run/test_bag.py checks every layout byte for byte against
rosbags' own serializer.
"""

from __future__ import annotations

import struct
from typing import Sequence

ENCAPSULATION = b"\x00\x01\x00\x00"  # CDR, little endian: what rosbag2 stores for 'cdr'
_SIZES = {"i": 4, "I": 4, "f": 4, "d": 8}


class Layout:
    """Build a message shape field by field; constants are given now, variables when packing."""

    def __init__(self) -> None:
        self._fmt = ["<4s"]  # struct codes of the whole message, encapsulation header first
        self._args: list[bytes | int] = [ENCAPSULATION]  # constants, or the index of a variable
        self._size = 0  # payload bytes so far: CDR aligns relative to the payload
        self._vars = 0

    def _pad(self, size: int) -> None:
        pad = -self._size % size
        if pad:
            self._fmt.append(f"{pad}x")
            self._size += pad

    def _const(self, data: bytes) -> None:
        self._fmt.append(f"{len(data)}s")
        self._args.append(data)
        self._size += len(data)

    def var(self, code: str, count: int = 1) -> "Layout":
        """``count`` variable numbers of one type: 'i' int32, 'I' uint32, 'f' float32, 'd' float64."""
        self._pad(_SIZES[code])
        self._fmt.append(f"{count}{code}")
        self._args.extend(range(self._vars, self._vars + count))
        self._vars += count
        self._size += _SIZES[code] * count
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
        return Packer(struct.Struct("".join(self._fmt)), self._args, self._vars)


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
