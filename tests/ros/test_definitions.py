"""The one table of message definitions (ros/definitions.py): every text and hash against an
independent source, and the cyclonedds structs built from it (ros2/idl.py) against mobot's CDR
writer and rosbags' own reading of the .msg text, byte for byte, for every type in the table."""

from __future__ import annotations

from functools import lru_cache

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mobot_cli.ros.definitions import CONTACTS_STATE, MESSAGES, PARTICIPANT_ENTITIES_INFO, RANGE, Field, structs
from mobot_cli.ros.sensor_cdr import CdrWriter
from tests.ros.test_wire import discovery_store

# gazebo_msgs' .msg files as gazebo_ros_pkgs ships them (ROS 2 branch), comments included:
# rosbags has no gazebo_msgs, so these are the independent source for ContactsState.
GAZEBO_MSGS = {
    "gazebo_msgs/msg/ContactState": """
string info                                   # text info on this contact
string collision1_name                        # name of contact collision1
string collision2_name                        # name of contact collision2
geometry_msgs/Wrench[] wrenches               # list of forces/torques
geometry_msgs/Wrench total_wrench             # sum of forces/torques in every DOF
geometry_msgs/Vector3[] contact_positions     # list of contact position
geometry_msgs/Vector3[] contact_normals       # list of contact normals
float64[] depths                              # list of penetration depths
""",
    "gazebo_msgs/msg/ContactsState": """
std_msgs/Header header                                   # stamp
gazebo_msgs/ContactState[] states            # array of geom pairs in contact
""",
}


@lru_cache(maxsize=None)
def _stores():
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    stores = {}
    for name in (Stores.ROS2_HUMBLE, Stores.ROS2_JAZZY):
        store = get_typestore(name)
        types = {}
        for msgtype, text in GAZEBO_MSGS.items():
            types.update(get_types_from_msg(text, msgtype))
        store.register(types)
        stores[name.name] = store
    return stores


def test_every_definition_and_hash_is_rosbags_own():
    stores = _stores()
    assert len(MESSAGES) == 17  # 13, a camera's Image, CompressedImage and CameraInfo, and TwistStamped
    jazzy_only = (PARTICIPANT_ENTITIES_INFO, RANGE)  # Humble's gid is 24 bytes; its Range has no variance
    for msgtype, (definition, rihs01) in MESSAGES.items():
        for name, store in stores.items():
            if msgtype not in jazzy_only or name == "ROS2_JAZZY":
                assert store.generate_msgdef(msgtype, ros_version=2)[0] == definition, (name, msgtype)
        if msgtype not in jazzy_only:
            assert stores["ROS2_HUMBLE"].hash_rihs01(msgtype) == rihs01 == stores["ROS2_JAZZY"].hash_rihs01(msgtype)
    assert stores["ROS2_JAZZY"].hash_rihs01(RANGE) == MESSAGES[RANGE][1]
    assert "float32 variance" not in stores["ROS2_HUMBLE"].generate_msgdef(RANGE, ros_version=2)[0]
    # rmw_dds_common's Gid is char[16]; its shipped hash reads char as uint8, as ROS 2's IDL does
    assert discovery_store(16).hash_rihs01(PARTICIPANT_ENTITIES_INFO) == MESSAGES[PARTICIPANT_ENTITIES_INFO][1]


def test_definitions_are_read_into_fields_dependencies_first():
    contacts = structs(CONTACTS_STATE)
    assert list(contacts) == ["builtin_interfaces/Time", "std_msgs/Header", "geometry_msgs/Vector3",
                              "geometry_msgs/Wrench", "gazebo_msgs/ContactState", "gazebo_msgs/ContactsState"]
    assert contacts["gazebo_msgs/ContactState"][3] == Field("wrenches", "geometry_msgs/Wrench", sequence=True)
    cloud = structs("sensor_msgs/msg/PointCloud2")
    assert [f.name for f in cloud["sensor_msgs/PointField"]] == ["name", "offset", "datatype", "count"]  # no constants
    info = structs(PARTICIPANT_ENTITIES_INFO)
    assert info["rmw_dds_common/Gid"] == (Field("data", "char", length=16),)
    assert info["rmw_dds_common/NodeEntitiesInfo"][0] == Field("node_namespace", "string", bound=256)
    for msgtype in MESSAGES:
        seen: set[str] = set()
        for key, fields in structs(msgtype).items():
            assert all(f.type in seen for f in fields if "/" in f.type), (msgtype, key)
            seen.add(key)
    with pytest.raises(ValueError, match="cannot read the field 'float64 x 1.0'"):
        structs("a/msg/B", "float64 x 1.0\n")


# ---- the structs built from the table write what mobot's CDR writer writes ----

CODES = {"bool": "?", "byte": "B", "char": "B", "int8": "b", "uint8": "B", "int16": "h", "uint16": "H",
         "int32": "i", "uint32": "I", "int64": "q", "uint64": "Q", "float32": "f", "float64": "d"}
BITS = {"int8": 8, "int16": 16, "int32": 32, "int64": 64}


def _primitive(type_: str):
    if type_ == "string":
        return st.text(st.characters(codec="utf-8", exclude_characters="\0"), max_size=6)
    if type_ == "bool":
        return st.booleans()
    if type_ in ("float32", "float64"):
        return st.floats(allow_nan=False, width=32 if type_ == "float32" else 64)
    if type_ in BITS:
        return st.integers(-2 ** (BITS[type_] - 1), 2 ** (BITS[type_] - 1) - 1)
    return st.integers(0, 2 ** (8 * {"B": 1, "H": 2, "I": 4, "Q": 8}[CODES[type_]]) - 1)


def _strategy(key: str, tables, classes):
    def field(f: Field):
        element = _strategy(f.type, tables, classes) if "/" in f.type else _primitive(f.type)
        if f.length is not None:
            return st.lists(element, min_size=f.length, max_size=f.length)
        return st.lists(element, max_size=3) if f.sequence else element

    return st.builds(classes[key], **{f.name: field(f) for f in tables[key]})


def _write(out: CdrWriter, key: str, value, tables) -> None:
    """mobot's CDR writer, walking the same fields (sequences: their length first)."""
    for f in tables[key]:
        items = getattr(value, f.name)
        if f.sequence:
            out.u32(len(items))
        for item in items if f.sequence or f.length is not None else [items]:
            if "/" in f.type:
                _write(out, f.type, item, tables)
            elif f.type == "string":
                out.string(item)
            else:
                out.pack(CODES[f.type], item)


@pytest.mark.parametrize("msgtype, suffix", [*((m, "") for m in MESSAGES), (PARTICIPANT_ENTITIES_INFO, "24")])
def test_every_type_round_trips_through_its_struct_to_mobots_bytes(msgtype, suffix):
    pytest.importorskip("cyclonedds")
    from mobot_cli.ros2 import idl

    tables = structs(msgtype, idl.HUMBLE_DISCOVERY if suffix else None)  # 24: Humble's ParticipantEntitiesInfo
    classes = {key: getattr(idl, key.split("/")[1] + (suffix if key.startswith("rmw_dds_common/") else ""))
               for key in tables}
    root = list(tables)[-1]
    store = _stores()["ROS2_HUMBLE" if suffix else "ROS2_JAZZY"]
    if not suffix:
        assert classes[root] is idl.TYPES[msgtype]

    @settings(max_examples=25, deadline=None)
    @given(sample=_strategy(root, tables, classes))
    def round_trip(sample):
        ours = CdrWriter()
        _write(ours, root, sample, tables)
        theirs = sample.serialize()
        assert theirs == ours.bytes()
        assert classes[root].deserialize(theirs).serialize() == theirs  # uint8[] reads back as bytes
        assert bytes(store.serialize_cdr(store.deserialize_cdr(theirs, msgtype), msgtype)) == theirs

    round_trip()
