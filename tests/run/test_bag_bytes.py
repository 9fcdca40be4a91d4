"""The bag's direct MCAP records (run/mcap_records.py) are the bytes rosbags' Writer.write makes.

Each run is recorded twice, once with messages appended to rosbags' open chunk directly (what
`mobot run` does) and once through ``Writer.write``, and the two folders must be equal byte for
byte: robots that come and go (their connections land in the open chunk between messages),
sensors at their own rates, and a 3D lidar whose scans fill chunks past rosbags' 1 MiB limit.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest

from mobot_cli.run import bag, mcap_records
from mobot_cli.run.execute import execute
from mobot_cli.run.prepare import prepare
from mobot_cli.sim.plan import CommandStep, RayAxis
from tests.sim.sensor_world import lidar, one_robot, planned

REPO = Path(__file__).resolve().parents[2]


def _through_writer(monkeypatch) -> None:
    monkeypatch.setattr(bag, "Records", lambda writer, direct=True: mcap_records.Records(writer, direct=False))


def _bag(folder: Path) -> dict[str, bytes]:
    return {name: (folder / "bag" / name).read_bytes() for name in ("bag.mcap", "metadata.yaml")}


def _chunk_sizes(path: Path) -> list[int]:
    """Uncompressed sizes of the file's chunks, from its summary (the independent mcap reader)."""
    from mcap.reader import make_reader

    with path.open("rb") as f:
        return [index.uncompressed_size for index in make_reader(f).get_summary().chunk_indexes]


def test_robots_that_come_and_go_give_the_writers_bytes(tmp_path, monkeypatch):
    prepared = prepare(REPO / "scenarios" / "events.yaml", ["log.formats=[csv, mcap]"])
    direct = execute(prepared.plan, prepared.resolved_yaml, tmp_path / "direct").out_dir
    _through_writer(monkeypatch)
    written = execute(prepared.plan, prepared.resolved_yaml, tmp_path / "writer").out_dir
    assert _bag(direct) == _bag(written)
    assert len(_bag(direct)["bag.mcap"]) > 100_000  # a real bag, several chunks


def test_sensor_scans_past_the_chunk_limit_give_the_writers_bytes(tmp_path, monkeypatch):
    velodyne = lidar("velodyne", samples=600, vertical=RayAxis(16, -0.2618, 0.2618), range_max=30.0,
                     xyz=(0.0, 0.0, 0.4), range_resolution=0.001)
    plan, resolved = planned(one_robot(tmp_path, x=2.2, y=0.0, yaw=0.0, duration=1.0), "mobot",
                             lidar(xyz=(0.0, 0.0, 0.3), range_max=3.0, noise_stddev=0.01), velodyne,
                             formats=("csv", "mcap"))
    plan = replace(plan, robots=(replace(plan.robots[0], commands=(CommandStep(step=60, linear=0.5, angular=0.0),)),))
    direct = execute(plan, resolved, tmp_path / "direct").out_dir
    _through_writer(monkeypatch)
    written = execute(plan, resolved, tmp_path / "writer").out_dir
    assert _bag(direct) == _bag(written)
    # Each 3D scan's PointCloud2 is ~150 kB: a chunk was closed at rosbags' limit, mid-batch.
    sizes = _chunk_sizes(direct / "bag" / "bag.mcap")
    assert len(sizes) >= 2 and max(sizes) > mcap_records.CHUNK_LIMIT, sizes


def test_a_writer_that_does_not_look_as_expected_gets_every_message(tmp_path):
    class Plain:
        storage = object()  # no chunk, no counts: not rosbags' McapWriter as known

        def __init__(self):
            self.calls = []

        def write(self, connection, timestamp, data):
            self.calls.append((connection, timestamp, data))

    writer = Plain()
    records = mcap_records.Records(writer)
    assert not records.direct
    records.write(7, [("a", b"1"), ("b", b"22")])
    assert writer.calls == [("a", 7, b"1"), ("b", 7, b"22")]


@pytest.mark.parametrize("direct", [True, False])
def test_records_keep_rosbags_counts_and_time_span(tmp_path, direct):
    from rosbags.rosbag2 import StoragePlugin, Writer

    writer = Writer(tmp_path / f"b{direct}", version=8, storage_plugin=StoragePlugin.MCAP)
    writer.open()
    conn = writer.add_connection("/x", "std_msgs/msg/String", msgdef=bag.MESSAGES["std_msgs/msg/String"][0],
                                 rihs01=bag.MESSAGES["std_msgs/msg/String"][1])
    records = mcap_records.Records(writer, direct)
    assert records.direct is direct
    records.write(5, [(conn, b"\x00\x01\x00\x00\x01\x00\x00\x00\x00\x00\x00\x00")])
    records.write(3, [(conn, b"\x00\x01\x00\x00\x01\x00\x00\x00\x00\x00\x00\x00")] * 2)
    assert (writer.counts[conn.id], writer.min_timestamp, writer.max_timestamp) == (3, 3, 5)
    writer.close()
    assert "message_count: 3" in (tmp_path / f"b{direct}" / "metadata.yaml").read_text()
