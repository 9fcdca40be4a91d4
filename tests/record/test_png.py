"""plot.png: the PNG file of trajectory.png holds exactly the pixels that were drawn."""

from __future__ import annotations

import io
import struct
import zlib

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image, ImageDraw

from mobot_cli.record.png import encode_rgb


def decoded(data: bytes) -> Image.Image:
    image = Image.open(io.BytesIO(data))
    image.load()
    return image


def chunks(data: bytes) -> list[bytes]:
    """Chunk types in order, each CRC checked."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    kinds, at = [], 8
    while at < len(data):
        (length,) = struct.unpack(">I", data[at:at + 4])
        kind, body = data[at + 4:at + 8], data[at + 8:at + 8 + length]
        assert struct.unpack(">I", data[at + 8 + length:at + 12 + length])[0] == zlib.crc32(kind + body)
        kinds.append(kind)
        at += 12 + length
    return kinds


def test_a_drawn_and_reduced_plot_decodes_to_the_same_pixels():
    image = Image.new("RGB", (600, 400), "white")
    draw = ImageDraw.Draw(image)
    draw.line([(10, 10), (590, 390), (20, 380)], fill=(31, 119, 180), width=4)
    draw.rectangle([100, 100, 200, 150], fill=(178, 178, 178), outline=(40, 40, 40))
    draw.text((300, 20), "x (m)", fill=(40, 40, 40))
    small = image.reduce(2)  # as trajectory.png: drawn at twice the size, then reduced
    data = encode_rgb(small)
    back = decoded(data)
    assert (back.mode, back.size) == ("RGB", (300, 200))
    assert back.tobytes() == small.tobytes()
    assert chunks(data) == [b"IHDR", b"IDAT", b"IEND"]


@settings(max_examples=40, deadline=None)
@given(st.integers(1, 40), st.integers(1, 30), st.integers(0, 2**32 - 1))
def test_any_rgb_image_round_trips(width, height, seed):
    pixels = np.random.default_rng(seed).integers(0, 256, size=(height, width, 3), dtype=np.uint8)
    image = Image.fromarray(pixels, "RGB")
    assert np.array_equal(np.asarray(decoded(encode_rgb(image))), pixels)


def test_a_trajectory_sized_picture_is_one_zlib_stream_of_its_filtered_rows():
    image = Image.new("RGB", (2400, 1800), "white")
    draw = ImageDraw.Draw(image)
    for k in range(0, 2400, 150):
        draw.line([(k, 0), (k, 1800)], fill=(226, 226, 226), width=2)
    draw.line([(100 + 9 * i, 900 + 600 * np.sin(i / 20)) for i in range(240)], fill=(31, 119, 180), width=4)
    small = image.reduce(2)
    data = encode_rgb(small)
    assert decoded(data).tobytes() == small.tobytes()
    rows = np.frombuffer(small.tobytes(), np.uint8).reshape(900, 3600)
    filtered = np.hstack([np.full((900, 1), 2, np.uint8), np.vstack([rows[:1], rows[1:] - rows[:-1]])])
    assert len(data) < 1.02 * len(zlib.compress(filtered.tobytes(), 1)) + 100


def test_other_modes_are_refused():
    with pytest.raises(ValueError, match="RGB image, not P"):
        encode_rgb(Image.new("P", (4, 4)))
