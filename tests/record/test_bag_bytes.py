"""The bag's direct MCAP records (ros/mcap_records.py) are the bytes rosbags' Writer.write makes.

Each run is recorded twice, once with messages appended to rosbags' open chunk directly (what
`mobot run` does) and once through ``Writer.write``, and the two folders must be equal byte for
byte: robots that come and go (their connections land in the open chunk between messages),
sensors at their own rates, and a 3D lidar whose scans fill chunks past rosbags' 1 MiB limit.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mobot_cli.plan import CommandStep, RayAxis
from mobot_cli.record import bag
from mobot_cli.ros import bag_metadata, mcap_records
from mobot_cli.run import execute
from mobot_cli.scenario.prepare import prepare
from tests.sim.sensor_world import lidar, one_robot, planned

REPO = Path(__file__).resolve().parents[2]


def _through_writer(monkeypatch) -> None:
    """Every message, connection and the metadata through rosbags' own Writer: the reference bag."""
    monkeypatch.setattr(bag, "Records", lambda writer, direct=True: mcap_records.Records(writer, direct=False))
    monkeypatch.setattr(bag_metadata, "add_connection",
                        lambda writer, topic, msgtype, msgdef, rihs01, profiles=(): writer.add_connection(
                            topic, msgtype, msgdef=msgdef, rihs01=rihs01, offered_qos_profiles=profiles))
    monkeypatch.setattr(bag_metadata, "close", lambda writer: writer.close())


def _without_ruamel(monkeypatch) -> None:
    """Any YAML rosbags would dump through ruamel fails the test: the direct writer has none."""
    from ruamel.yaml import YAML

    def dump(*args, **kwargs):
        raise AssertionError("ruamel.yaml dumped a document")

    monkeypatch.setattr(YAML, "dump", dump)


def _bag(folder: Path) -> dict[str, bytes]:
    return {name: (folder / "bag" / name).read_bytes() for name in ("bag.mcap", "metadata.yaml")}


def _both_ways(monkeypatch, plan, resolved: str, out: Path) -> tuple[Path, Path]:
    """The run folders of ``plan`` recorded directly (ruamel made to fail) and through rosbags'
    own Writer: the bag under test and its reference."""
    with monkeypatch.context() as patch:
        _without_ruamel(patch)
        direct = execute(plan, resolved, out / "direct").out_dir
    _through_writer(monkeypatch)
    return direct, execute(plan, resolved, out / "writer").out_dir


def _chunk_sizes(path: Path) -> list[int]:
    """Uncompressed sizes of the file's chunks, from its summary (the independent mcap reader)."""
    from mcap.reader import make_reader

    with path.open("rb") as f:
        return [index.uncompressed_size for index in make_reader(f).get_summary().chunk_indexes]


def test_robots_that_come_and_go_give_the_writers_bytes(tmp_path, monkeypatch):
    prepared = prepare(REPO / "scenarios" / "events.yaml", ["log.formats=[csv, mcap]"])
    direct, written = _both_ways(monkeypatch, prepared.plan, prepared.resolved_yaml, tmp_path)
    assert _bag(direct) == _bag(written)
    assert len(_bag(direct)["bag.mcap"]) > 100_000  # a real bag, several chunks


def test_sensor_scans_past_the_chunk_limit_give_the_writers_bytes(tmp_path, monkeypatch):
    velodyne = lidar("velodyne", samples=600, vertical=RayAxis(16, -0.2618, 0.2618), range_max=30.0,
                     xyz=(0.0, 0.0, 0.4), range_resolution=0.001)
    plan, resolved = planned(one_robot(tmp_path, x=2.2, y=0.0, yaw=0.0, duration=1.0), "mobot",
                             lidar(xyz=(0.0, 0.0, 0.3), range_max=3.0, noise_stddev=0.01), velodyne,
                             formats=("csv", "mcap"))
    plan = replace(plan, robots=(replace(plan.robots[0], commands=(CommandStep(step=60, linear=0.5, angular=0.0),)),))
    direct, written = _both_ways(monkeypatch, plan, resolved, tmp_path)
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


def test_a_namespace_long_enough_to_fold_the_metadata_gives_the_writers_bytes(tmp_path, monkeypatch):
    # ruamel moves a plain value past column 80 to the next line: these topic names are folded
    # in metadata.yaml (key at column 6) and some only in the MCAP file's copy (column 4).
    namespace = "/" + "n" * 56  # its joint_states topic: 70 characters, folded at 6, not at 4
    prepared = prepare(REPO / "scenarios" / "quickstart.yaml",
                       ["log.formats=[csv, mcap]", "duration=0.5", f"robots.0.namespace={namespace}"])
    direct, written = _both_ways(monkeypatch, prepared.plan, prepared.resolved_yaml, tmp_path)
    assert _bag(direct) == _bag(written)
    meta = _bag(direct)["metadata.yaml"].decode()
    assert f"      name: \n        {namespace}/joint_states\n" in meta and f"      name: {namespace}/odom\n" in meta


def _ruamel_text(document) -> str:
    from io import StringIO

    from ruamel.yaml import YAML

    yaml = YAML(typ="safe")
    yaml.default_flow_style = False
    stream = StringIO()
    yaml.dump(document, stream)
    return stream.getvalue()


_TOPIC = st.lists(st.from_regex(r"[A-Za-z_][A-Za-z0-9_]{0,30}", fullmatch=True), min_size=1, max_size=6).map(
    lambda parts: "/" + "/".join(parts))


@settings(max_examples=60, deadline=None)
@given(topics=st.lists(st.tuples(_TOPIC, st.sampled_from(["", bag_metadata.LATCHED_QOS]),
                                 st.integers(0, 2**40)), min_size=1, max_size=5),
       start=st.integers(0, 2**62), duration=st.integers(0, 2**62))
def test_metadata_text_is_what_ruamel_writes(topics, start, duration):
    info = {"version": 8, "storage_identifier": "mcap", "relative_file_paths": ["bag.mcap"],
            "duration": {"nanoseconds": duration}, "starting_time": {"nanoseconds_since_epoch": start},
            "message_count": sum(n for _, _, n in topics),
            "topics_with_message_count": [
                {"topic_metadata": {"name": name, "type": "sensor_msgs/msg/JointState",
                                    "serialization_format": "cdr", "offered_qos_profiles": qos,
                                    "type_description_hash": bag.MESSAGES["sensor_msgs/msg/JointState"][1]},
                 "message_count": n} for name, qos, n in topics],
            "compression_format": "", "compression_mode": "", "custom_data": None,
            "files": [{"path": "bag.mcap", "starting_time": {"nanoseconds_since_epoch": start},
                       "duration": {"nanoseconds": duration}, "message_count": 1}],
            "ros_distro": "rosbags"}
    # The MCAP file's copy (the mapping alone, stripped) and metadata.yaml (under one key).
    assert "\n".join(bag_metadata._mapping(info, 0)) == _ruamel_text(info).strip()
    outer = {"rosbag2_bagfile_information": info}
    assert "\n".join(bag_metadata._mapping(outer, 0)) + "\n" == _ruamel_text(outer)


def test_latched_qos_text_is_rosbags_dump():
    from rosbags.rosbag2.metadata import dump_qos_v8

    assert bag_metadata.latched_qos_text(bag_metadata.latched_qos()) == dump_qos_v8(bag_metadata.latched_qos())
    assert bag_metadata.latched_qos_text([]) == dump_qos_v8([]) == ""


def test_what_the_metadata_writer_does_not_know_goes_through_rosbags(tmp_path):
    from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime
    from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer

    zero = QosTime(0, 0)
    best_effort = [Qos(QosHistory.KEEP_LAST, 5, QosReliability.BEST_EFFORT, QosDurability.VOLATILE,
                       zero, zero, QosLiveliness.AUTOMATIC, zero, False)]
    folders = []
    for mine in (True, False):
        writer = Writer(tmp_path / str(mine) / "bag", version=8, storage_plugin=StoragePlugin.MCAP)
        writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
        writer.open()
        msgdef, rihs01 = bag.MESSAGES["std_msgs/msg/String"]
        for topic, profiles in (("/true", ()), ("/x y", ()), ("/q", best_effort), ("/l", bag_metadata.latched_qos())):
            if mine:
                bag_metadata.add_connection(writer, topic, "std_msgs/msg/String", msgdef, rihs01, profiles)
            else:
                writer.add_connection(topic, "std_msgs/msg/String", msgdef=msgdef, rihs01=rihs01,
                                      offered_qos_profiles=profiles)
        if mine:
            with pytest.raises(bag_metadata._Unknown):  # a custom QoS: rosbags writes the metadata
                bag_metadata._information(writer)
            bag_metadata.close(writer)
        else:
            writer.close()
        folders.append(_bag(tmp_path / str(mine)))
    assert folders[0] == folders[1]
    with pytest.raises(bag_metadata._Unknown):
        bag_metadata._scalar("/x y")
    with pytest.raises(bag_metadata._Unknown):
        bag_metadata._scalar("true")
