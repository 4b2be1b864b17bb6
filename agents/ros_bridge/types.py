"""The ROS 2 message types chronav speaks, their CDR and their RIHS01 type hashes, from rosbags.

Why rosbags (and not hand-written CDR): it is a maintained, pure-Python implementation of the
ROS 2 type system (the type stores of every distro, CDR with its encapsulation header, and the
REP-2011 RIHS01 hash computed from the type description, as ``rosidl`` does).  The two message
sets rosbags' store lacks are registered here from their upstream ``.msg`` text:

- ``people_msgs/msg/People`` (wg-perception/people, ros2 branch): what the ROS social-navigation
  layers consume (Nav2's social costmap layers, nav2_social_mpc_controller, CaBot).  HuNavSim's
  ``hunav_msgs/Agents`` carries far more (behaviour, goals, cylinders) that chronav does not
  track, and only HuNavSim reads it; ``People`` is the common denominator: name, position,
  velocity, reliability and tags (chronav puts the role and the group there).
- ``nav2_msgs/msg/CostmapFilterInfo`` (ros-navigation/navigation2): the costmap-filter info Nav2's
  keepout and speed filters read next to their mask.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any

from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore

#: the ROS 2 distro whose definitions are used (Jazzy: LTS, rmw_zenoh binary packages exist;
#: the hashes of the messages used here are the same in Kilted and Rolling)
DISTRO = Stores.ROS2_JAZZY

PERSON_MSG = """\
string name
geometry_msgs/Point position
geometry_msgs/Point velocity
float64 reliability
string[] tagnames
string[] tags
"""
PEOPLE_MSG = """\
std_msgs/Header header
people_msgs/Person[] people
"""
COSTMAP_FILTER_INFO_MSG = """\
std_msgs/Header header
uint8 type
string filter_mask_topic
float32 base
float32 multiplier
"""

EXTRA_TYPES: dict[str, str] = {
    "people_msgs/msg/Person": PERSON_MSG,
    "people_msgs/msg/People": PEOPLE_MSG,
    "nav2_msgs/msg/CostmapFilterInfo": COSTMAP_FILTER_INFO_MSG,
}


@lru_cache(maxsize=1)
def typestore() -> Typestore:
    """Jazzy's type store plus the message sets above (built once per process)."""
    store = get_typestore(DISTRO)
    for name, text in EXTRA_TYPES.items():
        store.register(get_types_from_msg(text, name))
    return store


def msg_class(type_name: str) -> Any:
    """The rosbags dataclass of ``pkg/msg/Name``."""
    return typestore().types[type_name]


def type_hash(type_name: str) -> str:
    """``RIHS01_<sha256>`` of the type description, as rosidl computes it (REP-2011)."""
    return typestore().hash_rihs01(type_name)


def dds_type_name(type_name: str) -> str:
    """``pkg/msg/Name`` -> ``pkg::msg::dds_::Name_``: the name rmw_zenoh puts in key expressions."""
    pkg, kind, name = type_name.split("/")
    return f"{pkg}::{kind}::dds_::{name}_"


def serialize(message: Any, type_name: str) -> bytes:
    """CDR (little endian) with its 4-byte encapsulation header, as rmw publishes it."""
    return bytes(typestore().serialize_cdr(message, type_name))


def deserialize(data: bytes, type_name: str) -> Any:
    return typestore().deserialize_cdr(data, type_name)
