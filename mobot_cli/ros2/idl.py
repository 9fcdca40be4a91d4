"""The ROS 2 message types mobot sends and takes, as cyclonedds IDL structs built from ros/definitions.py.

mobot writes the bytes itself (ros/messages.py, ros/sensor_cdr.py), but cyclonedds makes a
topic only for a type it can describe: its DDS name and its XTypes type information, which
discovery carries and which Cyclone uses to check incoming samples. These structs are that
description, made from the message definitions the bag embeds, field for field, so the two
cannot drift apart. ROS 2's IDL mapping: ``T[]`` is a sequence, ``T[N]`` an array,
``string<=N`` a bounded string, ``char`` is ``uint8``, and a type's DDS name is
``pkg::msg::dds_::Name_``. Tests also use the structs as a second, independent serializer.
Each struct is a module attribute by its ROS name (``idl.Odometry``, ``idl.Header``, ...).
"""

from dataclasses import dataclass
from types import new_class

from cyclonedds.idl import IdlStruct
from cyclonedds.idl import types as t

from mobot_cli.ros.definitions import MESSAGES, PARTICIPANT_ENTITIES_INFO, Field, structs

_PRIMITIVES = {"bool": bool, "byte": t.byte, "char": t.uint8, "int8": t.int8, "uint8": t.uint8,
               "int16": t.int16, "uint16": t.uint16, "int32": t.int32, "uint32": t.uint32,
               "int64": t.int64, "uint64": t.uint64, "float32": t.float32, "float64": t.float64, "string": str}


def build(msgtype: str, definition: str | None = None, suffix: str = "",
          known: dict[str, type] | None = None) -> dict[str, type]:
    """``known`` and the structs of ``msgtype`` and the types it uses that ``known`` lacks, by
    ROS name ('pkg/Name'); new classes are named ``Name`` + ``suffix``."""
    made = dict(known or {})
    for key, fields in structs(msgtype, definition).items():
        if key not in made:
            annotations = {field.name: _annotation(field, made) for field in fields}
            typename = key.replace("/", "::msg::dds_::") + "_"
            cls = new_class(key.split("/")[1] + suffix, (IdlStruct,), {"typename": typename},
                            lambda ns, a=annotations: ns.update(__annotations__=a, __module__=__name__))
            made[key] = dataclass(cls)
    return made


def _annotation(field: Field, made: dict[str, type]):
    element = made[field.type] if "/" in field.type else _PRIMITIVES[field.type]
    if field.bound is not None:
        element = t.bounded_str[field.bound]
    if field.sequence:
        return t.sequence[element]
    return t.array[element, field.length] if field.length is not None else element


def _export(made: dict[str, type]) -> None:
    for cls in made.values():
        if globals().setdefault(cls.__name__, cls) is not cls:
            raise TypeError(f"two ROS types are named {cls.__name__}")


_made: dict[str, type] = {}
for _msgtype in MESSAGES:
    _made = build(_msgtype, known=_made)
_export(_made)
# ROS type -> the struct that describes it on DDS
TYPES: dict[str, type] = {msgtype: _made[msgtype.replace("/msg/", "/")] for msgtype in MESSAGES}

# The one type that differs between distributions: rmw gids were 24 bytes until Iron, so
# Humble's ParticipantEntitiesInfo (the same DDS names) is built from the table's text with
# char[24]: ParticipantEntitiesInfo24, NodeEntitiesInfo24 and Gid24.
HUMBLE_DISCOVERY = MESSAGES[PARTICIPANT_ENTITIES_INFO][0].replace("char[16] data", "char[24] data")
assert HUMBLE_DISCOVERY != MESSAGES[PARTICIPANT_ENTITIES_INFO][0]
_export(build(PARTICIPANT_ENTITIES_INFO, HUMBLE_DISCOVERY, "24"))
