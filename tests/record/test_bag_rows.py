"""A bag packs a log row at once (record/bag.py ``log_row``, ros/mcap_records.py ``Row``): its
messages must be the bytes the one-message packers give (what ``--ros2`` publishes, checked
against rosbags' serializer in tests/ros/test_wire.py), its records what rosbags' Writer writes."""

from __future__ import annotations

import struct
from collections import namedtuple

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mobot_cli.plan import RobotPlan, SpawnPose
from mobot_cli.record.bag import MESSAGES, log_row
from mobot_cli.ros import mcap_records
from mobot_cli.ros import messages as rm
from mobot_cli.ros.cdr import Layout
from mobot_cli.sim.state import RobotState

Connection = namedtuple("Connection", "id topic")
_ORIGIN = '<origin xyz="0 0.1 0.05" rpy="-1.5708 0 0"/>'
URDFS = {
    # two wheels, one with a rotated origin (the general quaternion product)
    "wheels": f"""<robot name="w"><link name="base_link"/><link name="left"/><link name="right"/>
<joint name="left_joint" type="continuous"><parent link="base_link"/><child link="left"/>{_ORIGIN}
<axis xyz="0 0 1"/></joint>
<joint name="right_joint" type="revolute"><parent link="base_link"/><child link="right"/>
<origin xyz="0 -0.1 0.05"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>""",
    # a lift (prismatic), a finger that mimics it, and a fixed mast
    "lift": """<robot name="l"><link name="base_link"/><link name="mast"/><link name="lift"/><link name="finger"/>
<joint name="mast_joint" type="fixed"><parent link="base_link"/><child link="mast"/><origin xyz="0 0 0.3"/></joint>
<joint name="lift_joint" type="prismatic"><parent link="mast"/><child link="lift"/><axis xyz="0 0 1"/>
<origin xyz="0.1 0 0" rpy="0 0.3 0"/><limit lower="0" upper="1" effort="1" velocity="1"/></joint>
<joint name="finger_joint" type="prismatic"><parent link="lift"/><child link="finger"/><axis xyz="1 0 0"/>
<mimic joint="lift_joint" multiplier="-0.5" offset="0.01"/><limit lower="-1" upper="1" effort="1" velocity="1"/>
</joint></robot>""",
    "block": '<robot name="b"><link name="base_link"/></robot>',
}
JOINTS = {"wheels": ("left_joint", "right_joint"), "lift": ("lift_joint", "finger_joint"), "block": ()}
number = st.one_of(st.floats(min_value=-1e6, max_value=1e6, allow_nan=False), st.sampled_from([0.0, -0.0]))


def robot(kind: str, index: int) -> rm.RobotMessages:
    name = f"{kind}{index}"
    plan = RobotPlan(name=name, namespace=f"/{name}", frame_prefix=f"{name}/", urdf=URDFS[kind],
                     root_link="base_link", pose=SpawnPose(), drive=None)
    return rm.RobotMessages(plan, state(kind, [0.0] * 10, dict.fromkeys(JOINTS[kind], 0.0)))


def state(kind: str, numbers: list[float], joints: dict[str, float]) -> RobotState:
    """A state whose numbers come from ``numbers``; its joints as given (some may be missing)."""
    n = iter(numbers)
    positions = {j: joints.get(j, next(n)) for j in JOINTS[kind] if j in joints or kind != "lift"}
    return RobotState(*(next(n) for _ in range(7)), 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
                      joint_positions=positions, joint_velocities={j: v * 3.0 for j, v in positions.items()})


def one_by_one(clock, robots, tf, ns: int, stamp) -> list[tuple[int, bytes]]:
    """(channel id, data) of a sample's messages from the one-message packers, as --ros2 sends them."""
    out = [(clock.id, rm.CLOCK_PACKER.pack(stamp))] if clock else []
    tf_values: list[float] = []
    for (odom, cmd_vel, joint_states), messages, s in robots:
        out += [(odom.id, messages.odom(stamp, s)), (cmd_vel.id, messages.cmd_vel(s)),
                (joint_states.id, messages.joint_states(stamp, s))]
        messages.tf_values(stamp, s, tf_values)
    return out + [(tf.id, rm.tf_layout([m.frames for _, m, _ in robots]).pack(tf_values))]


@settings(max_examples=60, deadline=None)
@given(kinds=st.lists(st.sampled_from(sorted(URDFS)), min_size=1, max_size=4),
       numbers=st.lists(number, min_size=40, max_size=40), with_clock=st.booleans(),
       lift=st.dictionaries(st.sampled_from(JOINTS["lift"]), number, max_size=2),
       step=st.integers(0, 2**31 - 1), rate=st.sampled_from([50, 240, 1000]))
def test_a_rows_messages_are_the_one_message_packers_bytes(kinds, numbers, with_clock, lift, step, rate):
    clock, tf = Connection(1, "/clock"), Connection(2, "/tf")
    robots = []
    for i, kind in enumerate(kinds):
        connections = tuple(Connection(10 + 3 * i + k, f"/{kind}{i}/{k}") for k in range(3))
        numbers = numbers[9:] + numbers[:9]  # each robot its own numbers
        robots.append((connections, robot(kind, i), state(kind, numbers, lift)))
    row = log_row(clock if with_clock else None, [(c, m) for c, m, _ in robots], tf)
    ns, stamp = rm.stamp_of(step, rate)
    values = [ns, *stamp]
    for _, messages, s in robots:
        messages.row_values(s, values)
    data = row.pack(values)
    expected = one_by_one(with_clock and clock, robots, tf, ns, stamp)
    assert [(c.id, d) for c, d in row.messages(data)] == expected
    # the row is the MCAP Message records of those messages, end to end (record length: channel 2,
    # sequence 4, log and publish times 8 + 8, then the data)
    assert data == b"".join(mcap_records._MESSAGE.pack(5, 22 + len(d), cid, 0, ns, ns) + d for cid, d in expected)
    assert [(cid, data[at + 9:at + 11]) for cid, at in row.index] == [(cid, cid.to_bytes(2, "little"))
                                                                      for cid, _ in expected]


def test_a_sources_count_must_match_the_layouts_variables():
    with pytest.raises(ValueError, match="expected 2 sources, got 1"):
        Layout(b"").include(rm.CLOCK_LAYOUT, (0,))
    # a value used twice, a fixed number (-0.0 keeps its sign), alignment relative to the message
    fused = Layout(b"").raw(b"\x07").include(Layout().var("i").var("d", 3), (1, 0, -0.0, 0)).build()
    assert fused.pack([2.5, 9]) == b"\x07" + struct.pack("<4si4xddd", b"\x00\x01\x00\x00", 9, 2.5, -0.0, 2.5)


def _writer(path):
    from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer

    writer = Writer(path, version=8, storage_plugin=StoragePlugin.MCAP)
    writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
    writer.open()
    return writer


def _both_ways(folder, plan, sizes) -> list[tuple[bytes, bytes, dict]]:
    """The bag (MCAP file, metadata.yaml, counts) that ``plan`` gives through the direct records
    and through rosbags' Writer: rows of two sizes, single messages, the bag's own chunk flushes."""
    out = []
    for direct in (True, False):
        writer = _writer(folder / str(direct) / "bag")
        conns = [writer.add_connection(f"/t{i}", "std_msgs/msg/String", msgdef=MESSAGES["std_msgs/msg/String"][0],
                                       rihs01=MESSAGES["std_msgs/msg/String"][1]) for i in range(3)]
        records = mcap_records.Records(writer, direct)
        rows = {}
        for kind, n in (("row", sizes[0]), ("big row", sizes[1])):
            layout = Layout().var("d", n)
            rows[kind] = mcap_records.Row().add(conns[0], layout, range(1, n + 1)).add(
                conns[2], Layout().u32(n), ()).add(conns[1], layout, [0.5] * n).build()
        for t, (kind, flush) in enumerate(plan):
            ts = 1000 - 7 * t if t % 5 == 3 else 1000 + t  # log times need not rise
            if kind == "single":
                records.write(ts, [(conns[flush % 3], b"\x00\x01\x00\x00" + bytes(9 * flush))])
            else:
                n = sizes[0] if kind == "row" else sizes[1]
                records.write_row(ts, rows[kind], [ts] + [float(k) * t for k in range(n)])
            if flush == 3 and writer.storage.chunk.bio.tell():
                records.close_chunk()
        if writer.storage.chunk.bio.tell():
            records.close_chunk()
        counts = dict(writer.counts)
        writer.close()
        path = folder / str(direct) / "bag"
        out.append(((path / "bag.mcap").read_bytes(), (path / "metadata.yaml").read_bytes(), counts))
    return out


@settings(max_examples=12, deadline=None)
@given(plan=st.lists(st.tuples(st.sampled_from(["row", "big row", "single"]), st.integers(0, 3)),
                     min_size=1, max_size=40),
       sizes=st.tuples(st.integers(1, 400), st.integers(1, 20_000)))
def test_rows_and_single_messages_give_rosbags_writers_bytes(tmp_path_factory, plan, sizes):
    direct, written = _both_ways(tmp_path_factory.mktemp("rows"), plan, sizes)
    assert direct == written


def test_a_chunk_that_fills_within_a_row_closes_where_rosbags_closes_it(tmp_path):
    # Rows of ~320 kB: the fourth passes 1 MiB at its first message, which ends the chunk.
    plan = [("big row", 0)] * 3 + [("single", 1), ("big row", 0), ("row", 0), ("big row", 0)] * 2
    direct, written = _both_ways(tmp_path, plan, (10, 20_000))
    assert direct == written
    from mcap.reader import make_reader

    with (tmp_path / "True" / "bag" / "bag.mcap").open("rb") as f:
        sizes = [c.uncompressed_size for c in make_reader(f).get_summary().chunk_indexes]
    assert len(sizes) == 2 and mcap_records.CHUNK_LIMIT < sizes[0] < mcap_records.CHUNK_LIMIT + 200_000, sizes


def test_a_name_that_arrives_again_gets_rows_of_its_new_frames(tmp_path):
    import dataclasses
    from pathlib import Path

    import mcap.reader as mcap_reader
    import mcap_ros2.decoder as mcap_ros2

    from mobot_cli.record.bag import BagSink
    from mobot_cli.scenario.prepare import prepare
    from mobot_cli.timeline.loop import simulate
    from mobot_cli.timeline.records import Sample

    scenario = Path(__file__).resolve().parents[2] / "scenarios" / "quickstart.yaml"
    plan = prepare(scenario, ["duration=0.5"]).plan
    first = plan.robots[0]
    sink = BagSink(dataclasses.replace(plan, robots=()), tmp_path)
    samples = [r for r in simulate(plan) if isinstance(r, Sample)]
    for k, prefix in enumerate(("one/", "two/")):
        sink.spawned(0, "ghost", dataclasses.replace(first, name="ghost", namespace="/ghost", frame_prefix=prefix))
        for sample in samples[k * 5:k * 5 + 5]:
            sink.write(Sample(sample.step, {"ghost": sample.states[first.name]}))
    sink.close()
    with (tmp_path / "bag" / "bag.mcap").open("rb") as f:
        reader = mcap_reader.make_reader(f, decoder_factories=[mcap_ros2.DecoderFactory()])
        tf = [msg.transforms[0].child_frame_id for _, channel, _, msg in reader.iter_decoded_messages()
              if channel.topic == "/tf"]
    assert [name.split("/")[0] for name in tf] == ["one"] * 5 + ["two"] * 5, tf
