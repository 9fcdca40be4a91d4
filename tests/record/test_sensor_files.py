"""A lidar's .npy file as it grows: the rows NumPy loads, chunk by chunk, byte for byte."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from mobot_cli.plan import RayAxis
from mobot_cli.record.sensor_files import FLUSH_EVERY, NpyRows, read_header_rows, scan_dtype
from tests.sim.sensor_world import lidar


class _Scan:
    """What NpyRows reads of a sim.sensors.ScanData: its ranges (V, H)."""

    def __init__(self, ranges: np.ndarray):
        self.ranges = ranges


@pytest.mark.parametrize("spec", [lidar(samples=360), lidar("velodyne", samples=50, vertical=RayAxis(4, -0.2, 0.2))])
def test_rows_load_as_written_and_the_header_counts_whole_chunks(tmp_path, spec):
    dtype = scan_dtype(spec)
    rows_shape = (spec.vertical.samples if spec.vertical else 1, spec.horizontal.samples)
    rng = np.random.default_rng(4)
    scans = [rng.uniform(0.1, 8.0, rows_shape).astype(np.float32) for _ in range(FLUSH_EVERY * 2 + 7)]
    for scan in scans[::9]:
        scan[0, ::5] = np.inf  # no return
    path = tmp_path / "scan.npy"
    rows = NpyRows(path, dtype)
    times = [0.1 * i + 1e-9 * i * i for i in range(len(scans))]
    for i, (t, ranges) in enumerate(zip(times, scans)):
        rows.append(t, _Scan(ranges))
        assert read_header_rows(path) == (i + 1) // FLUSH_EVERY * FLUSH_EVERY  # only whole chunks count
    rows.close()
    loaded = np.load(path)
    assert read_header_rows(path) == len(loaded) == len(scans) and loaded.dtype == dtype
    assert loaded["t"].tolist() == times
    expected = np.stack(scans) if spec.vertical else np.stack(scans)[:, 0]
    assert loaded["ranges"].tobytes() == expected.tobytes()
    # the layout of the old writer: each row its time (<f8) then its ranges (<f4)
    body = path.read_bytes()[1024:]
    assert body == b"".join(struct.pack("<d", t) + r.astype("<f4").tobytes() for t, r in zip(times, scans))
