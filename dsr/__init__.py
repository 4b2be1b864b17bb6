"""DSR: the shared, replicated, multi-labelled graph every chronav agent holds (see CONTRACTS.md).

`DSRGraph` is the local replica and API; `join()` attaches it to Zenoh so that changes replicate
as CRDT deltas; the wire format is in docs/dsr_wire_format.md.
"""

from dsr.config import ZenohSettings, graph_name_from_env
from dsr.errors import (ConfigError, DSRError, EdgeNotFoundError, GraphFileError,
                        InvalidAttributeError, InvalidIdentifierError, NameTakenError,
                        NodeNotFoundError, PolicyError, PoseError, ReadOnlyGraphError,
                        TransactionError, WireError, WriteRefusedError)
from dsr.graph import DSRGraph
from dsr.model import Edge, Node
from dsr.policy import AllowAll, WritePolicy
from dsr.signals import SIGNALS, SpinPolicy
from dsr.transport import Replica, ReplicaStats, join

__all__ = [
    "AllowAll", "ConfigError", "DSRError", "DSRGraph", "Edge", "EdgeNotFoundError",
    "GraphFileError", "InvalidAttributeError", "InvalidIdentifierError", "NameTakenError", "Node",
    "NodeNotFoundError", "PolicyError", "PoseError", "ReadOnlyGraphError", "Replica", "ReplicaStats",
    "SIGNALS", "SpinPolicy", "TransactionError", "WireError", "WritePolicy", "ZenohSettings",
    "graph_name_from_env", "WriteRefusedError", "join",
]
