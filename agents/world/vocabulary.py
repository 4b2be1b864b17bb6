"""The DSR vocabulary: every node type, edge type, attribute and state the agents agree on, declared once.

Why a registry (after robocomp cortex's closed vocabulary): the agents are separate processes,
possibly on separate machines, that share nothing but the graph.  A misspelt ``"now_S"`` in one of
them would be a silent divergence; here each name is a constant (a ``StrEnum``: the members *are*
the strings that travel on the wire), each attribute has a kind, its writers and, for a state, the
set of values it may take.  Everything else is derived from this module:

- the write policy (``agents/world/write_policy.py`` generates ``write_policy.yaml`` from ``NODES``
  and ``EDGES``; ``tests/unit/test_vocabulary.py`` checks that the shipped file is what it generates);
- the checked graph every agent is handed (``agents/runtime/checked_graph.py``): a write of an
  unknown type, attribute or state is refused in the writer's own process, logged and counted;
- ``tests/unit/test_vocabulary_literals.py`` fails on a bare type or state string in agents/ or tools/.

Typed views (``ClockView`` ...) read a node's attributes with their declared types, so agents stop
writing ``float(node.attrs["now_s"])`` by hand.

``ActivityState`` is computed by the agenda library, which sits below this module in the import
layers (pyproject.toml): its one definition is ``agents/lib/states.py``, a leaf module below both,
re-exported here and by ``agents.lib.agenda``.
"""

from __future__ import annotations

import enum
import logging
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, replace
from enum import StrEnum
from functools import cache
from typing import Any, NamedTuple

from agents.lib.agent_plugins import KIND as AGENT_KIND, AgentSpec, package_of, specs as agent_specs
from agents.lib.registry import OWN_PACKAGE, RefusedExtension
from agents.lib.states import ActivityState

log = logging.getLogger("chronav.plugins")


class NodeType(StrEnum):
    """Node types."""

    WORLD = "world"
    ROOM = "room"
    DOOR = "door"
    CLOCK = "clock"
    ROBOT = "robot"
    PERSON = "person"
    OBJECT = "object"
    ACTIVITY = "activity"
    AGENDA = "agenda"
    AGENDA_REQUEST = "agenda_request"
    MISSION = "mission"
    INTENTION = "intention"
    SENSOR = "sensor"
    HEARTBEAT = "heartbeat"
    GROUND_TRUTH = "ground_truth"   # the simulated world's truth for simulated sensors (never for planning)


class EdgeType(StrEnum):
    """Edge types."""

    RT = "RT"                    # pose of the child in the parent's frame: x, y, theta
    IN = "in"                    # thing -> the room it is in
    CONNECTED = "connected"      # room -> room: the doors between them
    INTERACTING = "interacting"  # person -> person | object, while they interact
    HAS = "has"                  # activity -> its object
    PARTICIPANT = "participant"  # person -> activity
    STEP_OF = "step_of"          # intention -> mission
    TARGETS = "targets"          # mission -> what it is about


# ----------------------------------------------------------------------------------- state sets
class MissionState(StrEnum):
    """``mission.state``: pending -> active -> done | failed (written by the executive)."""

    PENDING = "pending"
    ACTIVE = "active"
    DONE = "done"
    FAILED = "failed"
    TERMINAL = enum.nonmember((DONE, FAILED))


class IntentionState(StrEnum):
    """``intention.state``: active -> done | failed (the executing agent) | cancelled (the executive)."""

    ACTIVE = "active"
    DONE = "done"
    FAILED = "failed"
    CANCELLED = "cancelled"


class IntentionKind(StrEnum):
    """``intention.kind``: drive to a goal pose (social navigation) or wait for an activity (executive)."""

    NAVIGATE = "navigate"
    WAIT = "wait"


class RequestState(StrEnum):
    """``agenda_request.state``: a staff tool creates it pending; the agenda answers accepted | refused."""

    PENDING = "pending"
    ACCEPTED = "accepted"
    REFUSED = "refused"
    ANSWERED = enum.nonmember((ACCEPTED, REFUSED))


class ClockMode(StrEnum):
    """``clock.mode``: how the simulator runs the sim clock (agents/sim_robot/agent.py says when)."""

    IDLE = "idle"
    STARTING = "starting"
    DRIVING = "driving"
    BUSY = "busy"
    FINISHED = "finished"


# ------------------------------------------------------------------- attribute keys, per type
class RoomAttr(StrEnum):
    POLYGON_X = "polygon_x"
    POLYGON_Y = "polygon_y"


class DoorAttr(StrEnum):
    X = "x"
    Y = "y"
    WIDTH = "width"
    ROOMS = "rooms"
    OPEN = "open"


class ClockAttr(StrEnum):
    NOW_S = "now_s"
    START_S = "start_s"
    END_S = "end_s"
    RATE = "rate"
    MODE = "mode"
    FINISHED = "finished"


class RobotAttr(StrEnum):
    RADIUS = "radius"
    KINEMATICS = "kinematics"
    MAX_SPEED = "max_speed"
    LASER_ANGLES = "laser_angles"
    POSE_STAMP = "pose_stamp"
    V = "v"
    VY = "vy"
    OMEGA = "omega"
    LASER_RANGES = "laser_ranges"
    NAV_ACTIVE = "nav_active"
    CMD_VX = "cmd_vx"
    CMD_VY = "cmd_vy"
    CMD_OMEGA = "cmd_omega"
    CMD_STAMP = "cmd_stamp"
    PATH_X = "path_x"
    PATH_Y = "path_y"
    PATH_COST = "path_cost"
    PLANNED_S = "planned_s"


class PersonAttr(StrEnum):
    ROLE = "role"
    SEEN_S = "seen_s"
    VX = "vx"
    VY = "vy"


class GroundTruthAttr(StrEnum):
    NAMES = "names"
    ROLES = "roles"
    X = "x"
    Y = "y"
    THETA = "theta"
    VX = "vx"
    VY = "vy"
    GROUPS = "groups"
    STAMP = "stamp"


class ObjectAttr(StrEnum):
    KIND = "kind"
    FORBIDDEN_WHILE_ACTIVE = "forbidden_while_active"
    FOOTPRINT_SHAPE = "footprint_shape"
    FOOTPRINT_DIMS = "footprint_dims"
    INTERACTION_SHAPE = "interaction_shape"
    INTERACTION_DIMS = "interaction_dims"
    R = "R"
    R_BAND = "R_band"
    ACTIVE = "active"


class ActivityAttr(StrEnum):
    ACTIVITY_ID = "activity_id"
    NAME = "name"
    OBJECT = "object"
    ROOM = "room"
    START_S = "start_s"
    END_S = "end_s"
    PARTICIPANTS = "participants"
    STATE = "state"
    SOURCE = "source"


class AgendaAttr(StrEnum):
    APPLIED = "applied"
    CHANGES = "changes"


class RequestAttr(StrEnum):
    CHANGE = "change"
    REQUESTED_BY = "requested_by"
    REQUESTED_S = "requested_s"
    STATE = "state"
    MESSAGE = "message"
    ANSWERED_S = "answered_s"


class MissionAttr(StrEnum):
    MISSION_ID = "mission_id"
    GOAL = "goal"
    TIME_S = "time_s"
    STATE = "state"
    DESCRIPTION = "description"
    REPLANS = "replans"
    STARTED_S = "started_s"
    FINISHED_S = "finished_s"
    REASON = "reason"
    PLAN = "plan"


class IntentionAttr(StrEnum):
    KIND = "kind"
    GOAL_X = "goal_x"
    GOAL_Y = "goal_y"
    GOAL_THETA = "goal_theta"
    GOAL_HAS_THETA = "goal_has_theta"
    UNTIL_S = "until_s"
    TARGET = "target"
    PASS_THROUGH = "pass_through"
    ROOMS = "rooms"
    MISSION_ID = "mission_id"
    STEP = "step"
    RULE = "rule"
    BINDINGS = "bindings"
    ISSUED_S = "issued_s"
    STATE = "state"
    REASON = "reason"
    REPLANS = "replans"
    PATH_X = "path_x"
    PATH_Y = "path_y"
    PATH_COST = "path_cost"
    PLANNED_S = "planned_s"


class SensorAttr(StrEnum):
    OBSERVED_S = "observed_s"


class HeartbeatAttr(StrEnum):
    BEAT = "beat"
    PID = "pid"
    WALL_S = "wall_s"
    PROBLEM = "problem"   # what keeps the agent from its job now, in a user's words ("" when nothing)


class PoseAttr(StrEnum):
    """The attributes of an ``RT`` edge."""

    X = "x"
    Y = "y"
    THETA = "theta"


class ConnectedAttr(StrEnum):
    DOOR = "door"
    DOORS = "doors"


# Well-known node names.
WORLD = "world"
CLOCK = "clock"
AGENDA = "agenda"
GROUND_TRUTH_PEOPLE = "ground_truth/people"
ACTIVITY_PREFIX = "activity/"
AGENDA_REQUEST_PREFIX = "agenda_request/"


def activity_name(activity_id: str) -> str:
    """The node name of agenda activity ``activity_id``: ``activity/<id>``."""
    return f"{ACTIVITY_PREFIX}{activity_id}"


def activity_id_of(name: str) -> str:
    """The id ``chronav agenda list`` shows for an ``activity/<id>`` node name."""
    return name.removeprefix(ACTIVITY_PREFIX)


def mission_name(mission_id: str) -> str:
    return f"mission/{mission_id}"


def intention_name(mission_id: str, attempt: int, step: int) -> str:
    """``intention/<mission>/<attempt>.<step>``: a new name for every (re)issue, so the executing
    agent sees a new node (and a new goal) whenever the executive replans."""
    return f"intention/{mission_id}/{attempt}.{step}"


def sensor_name(agent: str) -> str:
    return f"sensor/{agent}"


def heartbeat_name(agent: str) -> str:
    return f"heartbeat/{agent}"


# Attribute value kinds as the DSR stores them (docs/dsr_wire_format.md).
FLOAT, INT, BOOL, STR, FLOATS, STRS = "float", "int", "bool", "str", "floats", "strs"

# The writers of chronav's core vocabulary by their process names.  Which agents a run has is the
# registry's (``chronav.agents`` entry points, ``vocabulary().agents``), not a list here.
SIM_ROBOT, OBSERVER, RECOGNITION = "sim_robot", "human_observer", "object_recognition"
AGENDA_AGENT, EXECUTIVE, NAVIGATION, AGENDA_TOOL = "agenda", "executive", "social_navigation", "agenda_tool-*"
#: the optional ROS 2 bridge (chronav launch --ros): it creates pose missions from /goal_pose
ROS_BRIDGE = "ros_bridge"


class Attr(NamedTuple):
    """One attribute of a node type.

    ``writers`` may set it at any time; ``init_by`` (creators of the node) may give it only when
    they create the node (the robot's radius, a ROS goal's mission fields); ``values``, for a
    state, is the set of values it may take."""

    kind: str
    writers: tuple[str, ...] = ()
    init_by: tuple[str, ...] = ()
    values: type[StrEnum] | None = None


@dataclass(frozen=True)
class NodeSpec:
    """Who creates (and deletes) nodes of a type, and each attribute's kind and writers.

    ``deleters`` defaults to the creators; ``init_values`` narrows, per creator, the values some
    attribute may be given at creation (a staff tool creates a request ``pending`` only)."""

    type: str
    creators: tuple[str, ...]
    attrs: Mapping[str, Attr] = field(default_factory=dict)
    deleters: tuple[str, ...] | None = None
    init_values: Mapping[str, Mapping[str, tuple[str, ...]]] = field(default_factory=dict)

    @property
    def may_delete(self) -> tuple[str, ...]:
        return self.creators if self.deleters is None else self.deleters


@dataclass(frozen=True)
class EdgeSpec:
    """An edge type between node types, who writes it, and its attributes' kinds.  ``delete``:
    whether its writers may also delete it (the ROS bridge only ever sets the robot's pose)."""

    type: str
    src: tuple[str, ...]
    dst: tuple[str, ...]
    writers: tuple[str, ...]
    attrs: Mapping[str, str] = field(default_factory=dict)
    delete: bool = True


def _attrs(writers: str | tuple[str, ...], kinds: Mapping[StrEnum, str], *, init_only: bool = False,
           values: Mapping[StrEnum, type[StrEnum]] | None = None) -> dict[str, Attr]:
    """``kinds`` written by ``writers`` (at creation only with ``init_only``)."""
    who = (writers,) if isinstance(writers, str) else writers
    values = values or {}
    return {key: Attr(kind, () if init_only else who, who if init_only else (), values.get(key))
            for key, kind in kinds.items()}


def _merge(*parts: dict[str, Attr]) -> dict[str, Attr]:
    """Attributes of several writer groups; a key listed twice adds up its writers."""
    out: dict[str, Attr] = {}
    for part in parts:
        for key, attr in part.items():
            old = out.get(key)
            out[key] = attr if old is None else old._replace(writers=old.writers + attr.writers,
                                                             init_by=old.init_by + attr.init_by,
                                                             values=old.values or attr.values)
    return out


_R, _C, _D, _RB = RobotAttr, ClockAttr, DoorAttr, RequestAttr
_M, _I, _O, _A = MissionAttr, IntentionAttr, ObjectAttr, ActivityAttr
_G, _P = GroundTruthAttr, PersonAttr
_HEARTBEAT: dict[StrEnum, str] = {HeartbeatAttr.BEAT: INT, HeartbeatAttr.PID: INT, HeartbeatAttr.WALL_S: FLOAT, HeartbeatAttr.PROBLEM: STR}

NODES: dict[str, NodeSpec] = {spec.type: spec for spec in (
    NodeSpec(NodeType.WORLD, (SIM_ROBOT,)),
    NodeSpec(NodeType.ROOM, (SIM_ROBOT,), _attrs(SIM_ROBOT, {RoomAttr.POLYGON_X: FLOATS, RoomAttr.POLYGON_Y: FLOATS})),
    NodeSpec(NodeType.DOOR, (SIM_ROBOT,), _attrs(SIM_ROBOT, {_D.X: FLOAT, _D.Y: FLOAT, _D.WIDTH: FLOAT,
                                                             _D.ROOMS: STRS, _D.OPEN: BOOL})),
    NodeSpec(NodeType.CLOCK, (SIM_ROBOT,), _attrs(SIM_ROBOT, {_C.NOW_S: FLOAT, _C.START_S: FLOAT, _C.END_S: FLOAT,
                                                              _C.RATE: FLOAT, _C.MODE: STR, _C.FINISHED: BOOL},
                                                  values={_C.MODE: ClockMode})),
    NodeSpec(NodeType.ROBOT, (SIM_ROBOT,), _merge(
        # the body, given once when the simulator creates the robot
        _attrs(SIM_ROBOT, {_R.RADIUS: FLOAT, _R.KINEMATICS: STR, _R.MAX_SPEED: FLOAT, _R.LASER_ANGLES: FLOATS,
                           _R.NAV_ACTIVE: BOOL}, init_only=True),
        # the simulated robot's motion, or a ROS 2 robot's as the bridge reports it (--robot ros)
        _attrs((SIM_ROBOT, ROS_BRIDGE), {_R.POSE_STAMP: FLOAT, _R.V: FLOAT, _R.VY: FLOAT, _R.OMEGA: FLOAT,
                                         _R.LASER_RANGES: FLOATS}),
        _attrs(NAVIGATION, {_R.NAV_ACTIVE: BOOL, _R.CMD_VX: FLOAT, _R.CMD_VY: FLOAT, _R.CMD_OMEGA: FLOAT,
                            _R.CMD_STAMP: FLOAT, _R.PATH_X: FLOATS, _R.PATH_Y: FLOATS, _R.PATH_COST: FLOAT,
                            _R.PLANNED_S: FLOAT}))),
    NodeSpec(NodeType.PERSON, (OBSERVER,), _attrs(OBSERVER, {_P.ROLE: STR, _P.SEEN_S: FLOAT, _P.VX: FLOAT,
                                                             _P.VY: FLOAT})),
    # the simulator's people as they truly are, one list per attribute (agents/world/people.py); only
    # the human observer reads it, to perceive them with noise
    NodeSpec(NodeType.GROUND_TRUTH, (SIM_ROBOT,), _attrs(SIM_ROBOT, {
        _G.NAMES: STRS, _G.ROLES: STRS, _G.X: FLOATS, _G.Y: FLOATS, _G.THETA: FLOATS, _G.VX: FLOATS,
        _G.VY: FLOATS, _G.GROUPS: STRS, _G.STAMP: FLOAT})),
    NodeSpec(NodeType.OBJECT, (RECOGNITION,), _merge(
        _attrs(RECOGNITION, {_O.KIND: STR, _O.FORBIDDEN_WHILE_ACTIVE: BOOL, _O.FOOTPRINT_SHAPE: STR,
                             _O.FOOTPRINT_DIMS: FLOATS, _O.INTERACTION_SHAPE: STR, _O.INTERACTION_DIMS: FLOATS}),
        # R(t) and the activity flag of an object are the agenda's
        _attrs(AGENDA_AGENT, {_O.R: FLOAT, _O.R_BAND: INT, _O.ACTIVE: BOOL}))),
    NodeSpec(NodeType.ACTIVITY, (AGENDA_AGENT,), _attrs(AGENDA_AGENT, {
        _A.ACTIVITY_ID: STR, _A.NAME: STR, _A.OBJECT: STR, _A.ROOM: STR, _A.START_S: FLOAT, _A.END_S: FLOAT,
        _A.PARTICIPANTS: STRS, _A.STATE: STR, _A.SOURCE: STR}, values={_A.STATE: ActivityState})),
    NodeSpec(NodeType.AGENDA, (AGENDA_AGENT,), _attrs(AGENDA_AGENT, {AgendaAttr.APPLIED: STRS,
                                                                     AgendaAttr.CHANGES: STRS})),
    # staff tools (chronav agenda) ask for changes, created pending; only the agenda answers them.  The
    # agenda may create one too (its answer may arrive at a replica before the request itself).
    NodeSpec(NodeType.AGENDA_REQUEST, (AGENDA_TOOL, AGENDA_AGENT), _merge(
        _attrs(AGENDA_TOOL, {_RB.CHANGE: STR, _RB.REQUESTED_BY: STR, _RB.REQUESTED_S: FLOAT}),
        _attrs(AGENDA_TOOL, {_RB.STATE: STR}, init_only=True),
        _attrs(AGENDA_AGENT, {_RB.STATE: STR, _RB.MESSAGE: STR, _RB.ANSWERED_S: FLOAT},
               values={_RB.STATE: RequestState})),
        deleters=(AGENDA_TOOL,), init_values={AGENDA_TOOL: {_RB.STATE: (RequestState.PENDING,)}}),
    # the ROS bridge only creates missions (a /goal_pose, due now), never changes them; the executive runs them
    NodeSpec(NodeType.MISSION, (EXECUTIVE, ROS_BRIDGE), _merge(
        _attrs(EXECUTIVE, {_M.STARTED_S: FLOAT, _M.FINISHED_S: FLOAT, _M.REASON: STR, _M.PLAN: STRS}),
        _attrs(EXECUTIVE, {_M.MISSION_ID: STR, _M.GOAL: STR, _M.TIME_S: FLOAT, _M.STATE: STR,
                           _M.DESCRIPTION: STR, _M.REPLANS: INT}, values={_M.STATE: MissionState}),
        _attrs(ROS_BRIDGE, {_M.MISSION_ID: STR, _M.GOAL: STR, _M.TIME_S: FLOAT, _M.STATE: STR,
                            _M.DESCRIPTION: STR, _M.REPLANS: INT}, init_only=True)),
        deleters=(EXECUTIVE,)),
    NodeSpec(NodeType.INTENTION, (EXECUTIVE,), _merge(
        _attrs(EXECUTIVE, {_I.KIND: STR, _I.GOAL_X: FLOAT, _I.GOAL_Y: FLOAT, _I.GOAL_THETA: FLOAT,
                           _I.GOAL_HAS_THETA: BOOL, _I.UNTIL_S: FLOAT, _I.TARGET: STR, _I.PASS_THROUGH: BOOL,
                           _I.ROOMS: STRS, _I.MISSION_ID: STR, _I.STEP: INT, _I.RULE: STR, _I.BINDINGS: STRS,
                           _I.ISSUED_S: FLOAT}, values={_I.KIND: IntentionKind}),
        _attrs((EXECUTIVE, NAVIGATION), {_I.STATE: STR, _I.REASON: STR}, values={_I.STATE: IntentionState}),
        _attrs(NAVIGATION, {_I.REPLANS: INT, _I.PATH_X: FLOATS, _I.PATH_Y: FLOATS, _I.PATH_COST: FLOAT,
                            _I.PLANNED_S: FLOAT}))),
    # each perceiver (and, in lockstep, the executive) stamps the sim time it has caught up with
    # (agents/world/freshness.py)
    NodeSpec(NodeType.SENSOR, (OBSERVER, RECOGNITION, AGENDA_AGENT, EXECUTIVE),
             _attrs((OBSERVER, RECOGNITION, AGENDA_AGENT, EXECUTIVE), {SensorAttr.OBSERVED_S: FLOAT})),
    # every agent's loop stamps its own (agents/runtime/heartbeat.py); the launcher watches them.
    # Each registered agent is added as a writer by ``vocabulary()``
    NodeSpec(NodeType.HEARTBEAT, (ROS_BRIDGE,), _attrs(ROS_BRIDGE, _HEARTBEAT), deleters=()),
)}

_POSE: dict[str, str] = {PoseAttr.X: FLOAT, PoseAttr.Y: FLOAT, PoseAttr.THETA: FLOAT}

EDGES: tuple[EdgeSpec, ...] = (
    EdgeSpec(EdgeType.RT, (NodeType.WORLD,), (NodeType.ROOM, NodeType.ROBOT, NodeType.DOOR), (SIM_ROBOT,), _POSE),
    EdgeSpec(EdgeType.RT, (NodeType.WORLD,), (NodeType.ROBOT,), (ROS_BRIDGE,), _POSE, delete=False),  # --robot ros
    EdgeSpec(EdgeType.RT, (NodeType.WORLD,), (NodeType.PERSON,), (OBSERVER,), _POSE),
    EdgeSpec(EdgeType.RT, (NodeType.WORLD,), (NodeType.OBJECT,), (RECOGNITION,), _POSE),
    EdgeSpec(EdgeType.IN, (NodeType.ROBOT,), (NodeType.ROOM,), (SIM_ROBOT,)),
    EdgeSpec(EdgeType.IN, (NodeType.PERSON,), (NodeType.ROOM,), (OBSERVER,)),
    EdgeSpec(EdgeType.IN, (NodeType.OBJECT,), (NodeType.ROOM,), (RECOGNITION,)),
    EdgeSpec(EdgeType.CONNECTED, (NodeType.ROOM,), (NodeType.ROOM,), (SIM_ROBOT,),
             {ConnectedAttr.DOOR: STR, ConnectedAttr.DOORS: STRS}),
    EdgeSpec(EdgeType.INTERACTING, (NodeType.PERSON,), (NodeType.PERSON, NodeType.OBJECT), (OBSERVER,)),
    EdgeSpec(EdgeType.HAS, (NodeType.ACTIVITY,), (NodeType.OBJECT,), (AGENDA_AGENT,)),
    EdgeSpec(EdgeType.PARTICIPANT, (NodeType.PERSON,), (NodeType.ACTIVITY,), (AGENDA_AGENT,)),
    EdgeSpec(EdgeType.STEP_OF, (NodeType.INTENTION,), (NodeType.MISSION,), (EXECUTIVE,)),
)


# ------------------------------------------------------------------- the agents' declarations
@dataclass(frozen=True)
class Vocabulary:
    """The vocabulary a run uses: chronav's core table (``NODES``, ``EDGES``), each registered
    agent as a heartbeat writer, and the node and edge types plug-in agents declare (each owned by
    its agent alone).  ``agents``: the agents a run starts, in round order; ``refused``: the agent
    plug-ins refused at start (a broken description, or a declaration that claims another's type)."""

    nodes: Mapping[str, NodeSpec]
    edges: tuple[EdgeSpec, ...]
    agents: tuple[AgentSpec, ...] = ()
    refused: tuple[RefusedExtension, ...] = ()

    @property
    def names(self) -> tuple[str, ...]:
        """The agents' names, in round order."""
        return tuple(spec.name for spec in self.agents)

    def spec(self, name: str) -> AgentSpec:
        """The description of agent ``name``; KeyError listing the agents when it is not one."""
        for found in self.agents:
            if found.name == name:
                return found
        raise KeyError(f"no agent {name!r}; the agents are {', '.join(self.names)}")


def _owners(spec: NodeSpec) -> str:
    return ", ".join(spec.creators) or "nobody"


def _declaration_problem(agent: AgentSpec, nodes: Mapping[str, NodeSpec], edges: tuple[EdgeSpec, ...],
                         reserved: set[str]) -> str | None:
    """Why ``agent``'s declared types cannot join the vocabulary ``nodes``/``edges`` (None: they can).
    A plug-in owns what it declares: never a type, or an edge between types, that is another's."""
    if agent.name in reserved:
        return f"the name {agent.name!r} is a writer of chronav's own vocabulary"
    own: set[str] = set()
    for decl in agent.nodes:
        taken = nodes.get(decl.type)
        if taken is not None:
            return f"node type {decl.type!r} belongs to {_owners(taken)}: an agent declares only new types"
        if decl.type in own:
            return f"node type {decl.type!r} is declared twice"
        own.add(decl.type)
    for edge in agent.edges:
        for end in (*edge.src, *edge.dst):
            if end not in nodes and end not in own:
                return f"edge type {edge.type!r} names node type {end!r}, which no agent declares"
        existing = [spec for spec in edges if spec.type == edge.type]
        if existing and not (set(edge.src) <= own or set(edge.dst) <= own):
            writers = sorted({w for spec in existing for w in spec.writers})
            return (f"edge type {edge.type!r} belongs to {', '.join(writers)}: an agent writes it only from or "
                    "to node types it declares")
        kinds = {key: kind for spec in existing for key, kind in spec.attrs.items()}
        for key, kind in edge.attrs.items():
            if kinds.get(key, kind) != kind:
                return f"{edge.type} edge .{key} is {kinds[key]} in chronav's vocabulary, declared {kind}"
    return None


def take_in(agents: Iterable[tuple[AgentSpec, str]], refused: Iterable[RefusedExtension] = (),
            *, nodes: Mapping[str, NodeSpec] | None = None, edges: tuple[EdgeSpec, ...] | None = None) -> Vocabulary:
    """The core vocabulary (or ``nodes``/``edges``) with ``agents`` (description, package) taken in, in
    the order given: each a heartbeat writer; a plug-in's declared types added as its own, or the
    plug-in refused (RefusedExtension naming it, its package and why) and the rest taken in.  Pure:
    the same agents give the same vocabulary on every replica."""
    merged = dict(NODES if nodes is None else nodes)
    all_edges = EDGES if edges is None else edges
    reserved = {w for spec in merged.values() for w in (*spec.creators, *spec.may_delete)} | {
        w for spec in merged.values() for attr in spec.attrs.values() for w in (*attr.writers, *attr.init_by)} | {
        w for spec in all_edges for w in spec.writers}
    accepted: list[AgentSpec] = []
    refusals = list(refused)
    for agent, package in agents:
        # chronav's own agents write the core vocabulary under their names: only a plug-in may not
        problem = _declaration_problem(agent, merged, all_edges, set() if package == OWN_PACKAGE else reserved)
        if problem is not None:
            refusals.append(RefusedExtension(AGENT_KIND, agent.name, package, problem))
            continue
        for decl in agent.nodes:
            merged[decl.type] = NodeSpec(decl.type, (agent.name,),
                                         {key: Attr(kind, (agent.name,)) for key, kind in decl.attrs.items()})
        all_edges += tuple(EdgeSpec(e.type, tuple(e.src), tuple(e.dst), (agent.name,), dict(e.attrs))
                           for e in agent.edges)
        beat = merged[NodeType.HEARTBEAT]
        merged[NodeType.HEARTBEAT] = replace(beat, creators=(*beat.creators, agent.name),
                                             attrs=_merge(dict(beat.attrs), _attrs(agent.name, _HEARTBEAT)))
        accepted.append(agent)
    for refusal in refusals:
        log.warning("%s; the rest runs without it", refusal)
    return Vocabulary(merged, all_edges, tuple(accepted), tuple(refusals))


def _registered(own_only: bool) -> Vocabulary:
    found, refused = agent_specs()
    pairs = [(spec, package_of(spec.name)) for spec in found]
    if own_only:
        return take_in([(s, p) for s, p in pairs if p == OWN_PACKAGE])
    return take_in(pairs, refused)


@cache
def vocabulary() -> Vocabulary:
    """The vocabulary of this installation: the core, chronav's agents and every installed agent
    plug-in's declarations (read from the ``chronav.agents`` entry points once per process)."""
    return _registered(own_only=False)


@cache
def own_vocabulary() -> Vocabulary:
    """The core and chronav's own agents only: what the shipped write policy holds, whatever else is
    installed."""
    return _registered(own_only=True)


def edge_attrs(edge_type: str) -> dict[str, str]:
    """Every attribute an edge of ``edge_type`` may carry, with its kind (any end types)."""
    out: dict[str, str] = {}
    for spec in vocabulary().edges:
        if spec.type == edge_type:
            out.update(spec.attrs)
    return out


class VocabularyError(ValueError):
    """A write outside the vocabulary: unknown type, unknown attribute, wrong kind or state."""


def _kind_ok(kind: str, value: Any) -> bool:
    if kind == BOOL:
        return isinstance(value, bool)
    if kind == INT:
        return isinstance(value, int) and not isinstance(value, bool)
    if kind == FLOAT:
        return isinstance(value, (int, float)) and not isinstance(value, bool)
    if kind == STR:
        return isinstance(value, str)
    # Lists: the DSR itself refuses a list that mixes kinds (dsr/model.py), so the first item tells
    # floats from strings; not walking every item keeps a 360-ray laser scan cheap to check.
    if kind == FLOATS:
        return isinstance(value, (list, tuple)) and (not value or _kind_ok(FLOAT, value[0]))
    if kind == STRS:
        return isinstance(value, (list, tuple)) and (not value or isinstance(value[0], str))
    return False


def _known(names: Any) -> str:
    return ", ".join(sorted(str(n) for n in names)) or "none"


def check_node_type(node_type: str) -> NodeSpec:
    """The spec of ``node_type``, or VocabularyError listing the known types."""
    nodes = vocabulary().nodes
    spec = nodes.get(node_type)
    if spec is None:
        raise VocabularyError(f"unknown node type {node_type!r}; known: {_known(nodes)}")
    return spec


def check_attrs(node_type: str, attrs: Mapping[str, Any]) -> None:
    """VocabularyError naming the first attribute of ``attrs`` that is unknown for ``node_type``, of
    the wrong kind, or a state value outside its set (a typo fails in the writer's own process)."""
    spec = check_node_type(node_type)
    for key, value in attrs.items():
        declared = spec.attrs.get(key)
        if declared is None:
            raise VocabularyError(f"a {node_type} node has no attribute {key!r}; known: {_known(spec.attrs)}")
        if not _kind_ok(declared.kind, value):
            raise VocabularyError(f"{node_type}.{key} must be {declared.kind}, got {value!r}")
        if declared.values is not None and value not in declared.values.__members__.values():
            raise VocabularyError(f"{node_type}.{key} cannot be {value!r}; it is one of: "
                                  f"{', '.join(str(v) for v in declared.values)}")


def check_edge(edge_type: str, attrs: Mapping[str, Any]) -> None:
    """VocabularyError naming an unknown edge type, or an attribute it does not carry / of the wrong kind."""
    kinds = edge_attrs(edge_type)
    edges = vocabulary().edges
    if not any(spec.type == edge_type for spec in edges):
        raise VocabularyError(f"unknown edge type {edge_type!r}; known: {_known({e.type for e in edges})}")
    for key, value in attrs.items():
        kind = kinds.get(key)
        if kind is None:
            raise VocabularyError(f"a {edge_type} edge has no attribute {key!r}; known: {_known(kinds)}")
        if not _kind_ok(kind, value):
            raise VocabularyError(f"{edge_type} edge .{key} must be {kind}, got {value!r}")


# ----------------------------------------------------------------------------------- typed views
def _get(attrs: Mapping[str, Any], key: str, default: Any) -> Any:
    value = attrs.get(key, default)
    return default if value is None else value


@dataclass(frozen=True)
class ClockView:
    now_s: float
    start_s: float
    end_s: float
    mode: str
    finished: bool

    @classmethod
    def of(cls, graph: Any) -> ClockView | None:
        node = graph.get_node_by_name(CLOCK)
        if node is None or node.type != NodeType.CLOCK:
            return None
        a = node.attrs
        return cls(float(_get(a, "now_s", 0.0)), float(_get(a, "start_s", 0.0)), float(_get(a, "end_s", 0.0)),
                   str(_get(a, "mode", ClockMode.IDLE)), bool(_get(a, "finished", False)))


def now_s(graph: Any) -> float | None:
    """The sim time the DSR's clock shows, or None before the simulator wrote it (or if it is not a number)."""
    clock = graph.get_node_by_name(CLOCK)
    value = None if clock is None or clock.type != NodeType.CLOCK else clock.attrs.get(ClockAttr.NOW_S)
    return float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) else None


@dataclass(frozen=True)
class RobotView:
    """What the simulator and the navigation publish on the robot node."""

    node_id: int
    name: str
    pose_stamp: float
    nav_active: bool
    laser_ranges: tuple[float, ...]
    laser_angles: tuple[float, ...]

    @classmethod
    def from_node(cls, node: Any) -> RobotView:
        a = node.attrs
        return cls(node.id, node.name, float(_get(a, "pose_stamp", -1.0)), bool(_get(a, "nav_active", False)),
                   tuple(float(v) for v in _get(a, "laser_ranges", [])),
                   tuple(float(v) for v in _get(a, "laser_angles", [])))


@dataclass(frozen=True)
class ActivityView:
    id: str
    name: str
    object: str
    room: str
    start_s: float
    end_s: float
    participants: tuple[str, ...]
    state: str

    @classmethod
    def from_node(cls, node: Any) -> ActivityView:
        a = node.attrs
        return cls(str(_get(a, "activity_id", activity_id_of(node.name))), str(_get(a, "name", "")),
                   str(_get(a, "object", "")), str(_get(a, "room", "")), float(_get(a, "start_s", 0.0)),
                   float(_get(a, "end_s", 0.0)), tuple(str(p) for p in _get(a, "participants", [])),
                   str(_get(a, "state", ActivityState.SCHEDULED)))

    @classmethod
    def named(cls, graph: Any, name: str) -> ActivityView | None:
        """The activity node called ``name`` (``activity/<id>``), or None."""
        node = graph.get_node_by_name(name)
        if node is None or node.type != NodeType.ACTIVITY:
            return None
        try:
            return cls.from_node(node)
        except (TypeError, ValueError):
            return None

    @property
    def running(self) -> bool:
        return self.state == ActivityState.RUNNING

    @property
    def ended(self) -> bool:
        return self.state in ActivityState.ENDED


def activities(graph: Any) -> list[ActivityView]:
    out = []
    for node in graph.nodes_of_type(NodeType.ACTIVITY):
        try:
            out.append(ActivityView.from_node(node))
        except (TypeError, ValueError):
            continue
    return out


@dataclass(frozen=True)
class MissionView:
    node_id: int
    mission_id: str
    goal: str
    time_s: float
    state: str
    replans: int
    started_s: float | None = None
    finished_s: float | None = None
    reason: str = ""

    @classmethod
    def from_node(cls, node: Any) -> MissionView:
        a = node.attrs
        started, finished = a.get("started_s"), a.get("finished_s")
        return cls(node.id, str(_get(a, "mission_id", node.name.removeprefix("mission/"))), str(_get(a, "goal", "")),
                   float(_get(a, "time_s", 0.0)), str(_get(a, "state", MissionState.PENDING)),
                   int(_get(a, "replans", 0)), None if started is None else float(started),
                   None if finished is None else float(finished), str(_get(a, "reason", "")))

    @property
    def terminal(self) -> bool:
        return self.state in MissionState.TERMINAL


def missions(graph: Any) -> list[MissionView]:
    """Every readable mission node, in the order they are due (time, then id)."""
    out = []
    for node in graph.nodes_of_type(NodeType.MISSION):
        try:
            out.append(MissionView.from_node(node))
        except (TypeError, ValueError):
            continue
    return sorted(out, key=lambda m: (m.time_s, m.mission_id))


@dataclass(frozen=True)
class IntentionView:
    node_id: int
    name: str
    mission_id: str
    kind: str
    state: str
    step: int
    issued_s: float
    rule: str = ""
    goal: tuple[float, float, float | None] | None = None   # (x, y, theta or None) of a navigate intention
    until_s: float | None = None                            # end of the awaited activity (wait)
    target: str = ""
    rooms: tuple[str, ...] = ()
    pass_through: bool = False
    reason: str = ""
    replans: int = 0                                        # paths the navigation adopted after the first

    @classmethod
    def from_node(cls, node: Any) -> IntentionView:
        a = node.attrs
        goal = None
        if a.get("goal_x") is not None and a.get("goal_y") is not None:
            theta = float(_get(a, "goal_theta", 0.0)) if _get(a, "goal_has_theta", True) else None
            goal = (float(a["goal_x"]), float(a["goal_y"]), theta)
        until = a.get("until_s")
        return cls(node.id, node.name, str(_get(a, "mission_id", "")), str(_get(a, "kind", IntentionKind.NAVIGATE)),
                   str(_get(a, "state", IntentionState.ACTIVE)), int(_get(a, "step", 0)),
                   float(_get(a, "issued_s", 0.0)), str(_get(a, "rule", "")), goal,
                   None if until is None else float(until), str(_get(a, "target", "")),
                   tuple(str(r) for r in _get(a, "rooms", [])), bool(_get(a, "pass_through", False)),
                   str(_get(a, "reason", "")), int(_get(a, "replans", 0)))

    @property
    def active(self) -> bool:
        return self.state == IntentionState.ACTIVE


def intentions(graph: Any, mission_id: str | None = None) -> list[IntentionView]:
    """Every readable intention (of one mission when ``mission_id`` is given)."""
    out = []
    for node in graph.nodes_of_type(NodeType.INTENTION):
        try:
            view = IntentionView.from_node(node)
        except (TypeError, ValueError):
            continue
        if mission_id is None or view.mission_id == mission_id:
            out.append(view)
    return out
