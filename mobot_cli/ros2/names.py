"""How ROS 2 names things on DDS, and the settings a ROS user sets in the environment.

From the ROS 2 design article "Topic and Service name mapping to DDS" and rmw_cyclonedds:
a topic ``/ns/odom`` is the DDS topic ``rt/ns/odom``, a type ``nav_msgs/msg/Odometry`` the
DDS type ``nav_msgs::msg::dds_::Odometry_``; services use ``rq/<name>Request`` and
``rr/<name>Reply``. A wrong type name matches nothing, silently, so every name is made here.
Nothing here imports cyclonedds.
"""

from __future__ import annotations

import re
from typing import Mapping

from mobot_cli.errors import Location, UsageError

MAX_DOMAIN_ID = 232  # the highest id whose RTPS ports fit in 16 bits (ROS 2 "domain ID" docs)
FASTDDS_VENDOR = "1.15"  # eProsima's RTPS vendor id, as Cyclone's IgnoreTypeInformation takes it
NODE_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
NAMESPACE = re.compile(r"^/([A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*)?$")
MAX_TOPIC = 255 - 8  # rmw's limit on a full topic name (DDS allows 256 with room for prefixes)
LONGEST_SUFFIX = "/robot_description"  # the longest topic mobot makes under a robot's namespace
OLD_GID_DISTROS = ("foxy", "galactic", "humble")  # rmw_dds_common's Gid was char[24] before Iron


def topic(name: str) -> str:
    """The DDS topic of a ROS topic: ``/mobot/odom`` -> ``rt/mobot/odom``."""
    return "rt/" + name.lstrip("/")


def dds_type(msgtype: str) -> str:
    """The DDS type name of a ROS type: ``nav_msgs/msg/Odometry`` -> ``nav_msgs::msg::dds_::Odometry_``."""
    package, kind, name = msgtype.split("/")
    return f"{package}::{kind}::dds_::{name}_"


def ros_type(dds_name: str) -> str:
    """The ROS type of a DDS type name (the inverse of ``dds_type``)."""
    package, kind, _, name = dds_name.split("::")
    return f"{package}/{kind}/{name[:-1]}"


def join(namespace: str, name: str) -> str:
    """A topic under a namespace: ``join('/r1', 'odom')`` -> ``/r1/odom``; ``/`` is the root."""
    return namespace.rstrip("/") + "/" + name


def check_node(name: str, namespace: str, where: Location | None = None) -> None:
    """A UsageError unless ROS 2 accepts ``name`` as a node name and ``namespace`` as its namespace."""
    if not NODE_NAME.match(name):
        raise UsageError(f"'{name}' is not a valid ROS 2 node name", location=where,
                         hint="Use letters, digits and '_', not starting with a digit, e.g. mobot.")
    check_namespace(namespace, where)


def check_namespace(namespace: str, where: Location | None = None) -> None:
    """A UsageError unless ``namespace`` is a valid absolute ROS 2 namespace (rmw's rules) short
    enough for every topic mobot makes under it."""
    if not NAMESPACE.match(namespace):
        raise UsageError(f"'{namespace}' is not a valid ROS 2 namespace", location=where,
                         hint="Start with '/', and use names of letters, digits and '_' separated by "
                              "'/', not starting with a digit, e.g. /robot1.")
    if len(namespace.rstrip("/") + LONGEST_SUFFIX) > MAX_TOPIC:
        raise UsageError(f"namespace '{namespace[:24]}...' is too long for ROS 2", location=where,
                         hint=f"Keep it under {MAX_TOPIC - len(LONGEST_SUFFIX)} characters: ROS 2 topic "
                              f"names have at most {MAX_TOPIC}.")


def domain_id(configured: int | None, env: Mapping[str, str]) -> int:
    """The domain to join: the configured one, else ``ROS_DOMAIN_ID``, else 0 (as rcl does)."""
    if configured is not None:
        return configured
    text = env.get("ROS_DOMAIN_ID", "").strip()
    if not text:
        return 0
    if not text.isdigit() or int(text) > MAX_DOMAIN_ID:
        raise UsageError(f"environment variable ROS_DOMAIN_ID='{text}' is not a ROS 2 domain id",
                         hint=f"Use a whole number from 0 to {MAX_DOMAIN_ID} (0 to 101 is safe everywhere), "
                              "or unset it for domain 0.")
    return int(text)


def gid_size(env: Mapping[str, str]) -> int:
    """Bytes of an rmw gid in ros_discovery_info: 24 up to Humble, 16 from Iron on."""
    return 24 if env.get("ROS_DISTRO", "").strip().lower() in OLD_GID_DISTROS else 16


def discovery_config(env: Mapping[str, str], ignore_fastdds_type_information: bool) -> str:
    """Cyclone DDS configuration for the ROS discovery settings in ``env``, as rmw_cyclonedds
    builds it (``ROS_AUTOMATIC_DISCOVERY_RANGE``, ``ROS_STATIC_PEERS``, Humble's
    ``ROS_LOCALHOST_ONLY``), followed by the user's own ``CYCLONEDDS_URI``, which wins."""
    scope = env.get("ROS_AUTOMATIC_DISCOVERY_RANGE", "").strip().upper()
    if not scope and env.get("ROS_LOCALHOST_ONLY", "").strip() == "1":
        scope = "LOCALHOST"
    if scope not in ("", "SUBNET", "LOCALHOST", "OFF", "SYSTEM_DEFAULT"):
        raise UsageError(f"environment variable ROS_AUTOMATIC_DISCOVERY_RANGE='{scope}' is not a discovery range",
                         hint="Use SUBNET, LOCALHOST, OFF or SYSTEM_DEFAULT, or unset it.")
    peers = [p.strip() for p in env.get("ROS_STATIC_PEERS", "").replace(",", ";").split(";") if p.strip()]
    parts = []
    if ignore_fastdds_type_information:  # Fast DDS 3 (Kilted) type information that Cyclone cannot parse
        parts.append(f"<Compatibility><IgnoreTypeInformation>{FASTDDS_VENDOR}</IgnoreTypeInformation></Compatibility>")
    if scope in ("LOCALHOST", "OFF"):
        parts.append("<General><AllowMulticast>false</AllowMulticast></General>")
    if scope == "OFF":
        parts.append("<Discovery><ParticipantIndex>none</ParticipantIndex><Tag>ros_discovery_off</Tag></Discovery>")
    elif scope in ("LOCALHOST", "SUBNET") and (peers or scope == "LOCALHOST"):
        listed = (["localhost"] if scope == "LOCALHOST" else []) + peers
        parts.append("<Discovery><ParticipantIndex>auto</ParticipantIndex>"
                     "<MaxAutoParticipantIndex>32</MaxAutoParticipantIndex><Peers>"
                     + "".join(f'<Peer address="{_xml(p)}"/>' for p in listed) + "</Peers></Discovery>")
    config = "<CycloneDDS><Domain>" + "".join(parts) + "</Domain></CycloneDDS>"
    user = env.get("CYCLONEDDS_URI", "").strip()
    return f"{config},{user}" if user else config


def _xml(text: str) -> str:
    return text.replace("&", "&amp;").replace('"', "&quot;").replace("<", "&lt;")
