"""The DSR vocabulary: every node type, edge type and attribute the agents agree on, declared once.

Why a registry (after robocomp cortex's closed vocabulary): the agents are separate processes,
possibly on separate machines, that share nothing but the graph.  A misspelt ``"now_S"`` in one of
them would be a silent divergence; here each name is a constant, each attribute has a type and an
owner, and ``tests/unit/test_vocabulary.py`` checks that the write policy
(``agents/world/write_policy.yaml``) grants exactly these writes.

Typed views (``ClockView`` ...) read a node's attributes with their declared types, so agents stop
writing ``float(node.attrs["now_s"])`` by hand.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any


class NodeType:
    """Node types (plain strings: they travel on the wire as they are)."""

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


class EdgeType:
    """Edge types."""

    RT = "RT"                    # pose of the child in the parent's frame: x, y, theta
    IN = "in"                    # thing -> the room it is in
    CONNECTED = "connected"      # room -> room: the doors between them
    INTERACTING = "interacting"  # person -> person | object, while they interact
    HAS = "has"                  # activity -> its object
    PARTICIPANT = "participant"  # person -> activity
    STEP_OF = "step_of"          # intention -> mission
    TARGETS = "targets"          # mission -> what it is about


class MissionState:
    """``mission.state``: pending -> active -> done | failed (written by the executive)."""

    PENDING = "pending"
    ACTIVE = "active"
    DONE = "done"
    FAILED = "failed"
    TERMINAL = (DONE, FAILED)


class IntentionState:
    """``intention.state``: active -> done | failed (the executing agent) | cancelled (the executive)."""

    ACTIVE = "active"
    DONE = "done"
    FAILED = "failed"
    CANCELLED = "cancelled"


class IntentionKind:
    """``intention.kind``: drive to a goal pose (social navigation) or wait for an activity (executive)."""

    NAVIGATE = "navigate"
    WAIT = "wait"


class ActivityState:
    """``activity.state`` (the agenda library's states, as they travel on the wire)."""

    SCHEDULED = "scheduled"
    UPCOMING = "upcoming"
    RUNNING = "running"
    FINISHED = "finished"
    CANCELLED = "cancelled"
    ENDED = (FINISHED, CANCELLED)


# Well-known node names.
WORLD = "world"
CLOCK = "clock"
AGENDA = "agenda"
GROUND_TRUTH_PEOPLE = "ground_truth/people"
ACTIVITY_PREFIX = "activity/"


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

# The agents (writers) by their process names.
SIM_ROBOT, OBSERVER, RECOGNITION = "sim_robot", "human_observer", "object_recognition"
AGENDA_AGENT, EXECUTIVE, NAVIGATION, AGENDA_TOOL = "agenda", "executive", "social_navigation", "agenda_tool-*"
ALL_AGENTS = (SIM_ROBOT, OBSERVER, RECOGNITION, AGENDA_AGENT, NAVIGATION, EXECUTIVE)
#: the optional ROS 2 bridge (chronav launch --ros): it creates pose missions from /goal_pose
ROS_BRIDGE = "ros_bridge"


@dataclass(frozen=True)
class NodeSpec:
    """Who creates (and deletes) nodes of a type, and each attribute's kind and writers."""

    type: str
    creators: tuple[str, ...]
    attrs: Mapping[str, tuple[str, tuple[str, ...]]] = field(default_factory=dict)


@dataclass(frozen=True)
class EdgeSpec:
    """An edge type between node types, who writes it, and its attributes' kinds."""

    type: str
    src: tuple[str, ...]
    dst: tuple[str, ...]
    writers: tuple[str, ...]
    attrs: Mapping[str, str] = field(default_factory=dict)


def _attrs(writer: str | tuple[str, ...], **kinds: str) -> dict[str, tuple[str, tuple[str, ...]]]:
    writers = (writer,) if isinstance(writer, str) else writer
    return {key: (kind, writers) for key, kind in kinds.items()}


NODES: dict[str, NodeSpec] = {spec.type: spec for spec in (
    NodeSpec(NodeType.WORLD, (SIM_ROBOT,)),
    NodeSpec(NodeType.ROOM, (SIM_ROBOT,), _attrs(SIM_ROBOT, polygon_x=FLOATS, polygon_y=FLOATS)),
    NodeSpec(NodeType.DOOR, (SIM_ROBOT,), _attrs(SIM_ROBOT, x=FLOAT, y=FLOAT, width=FLOAT, rooms=STRS, open=BOOL)),
    NodeSpec(NodeType.CLOCK, (SIM_ROBOT,), _attrs(SIM_ROBOT, now_s=FLOAT, start_s=FLOAT, end_s=FLOAT, rate=FLOAT,
                                                  mode=STR, finished=BOOL)),
    NodeSpec(NodeType.ROBOT, (SIM_ROBOT,), {
        **_attrs(SIM_ROBOT, radius=FLOAT, kinematics=STR, max_speed=FLOAT, laser_angles=FLOATS),
        # the simulated robot's motion, or a ROS 2 robot's as the bridge reports it (--robot ros)
        **_attrs((SIM_ROBOT, ROS_BRIDGE), pose_stamp=FLOAT, v=FLOAT, vy=FLOAT, omega=FLOAT, laser_ranges=FLOATS),
        **_attrs((SIM_ROBOT, NAVIGATION), nav_active=BOOL),
        **_attrs(NAVIGATION, cmd_vx=FLOAT, cmd_vy=FLOAT, cmd_omega=FLOAT, cmd_stamp=FLOAT, path_x=FLOATS,
                 path_y=FLOATS, path_cost=FLOAT, planned_s=FLOAT)}),
    NodeSpec(NodeType.PERSON, (OBSERVER,), _attrs(OBSERVER, role=STR, seen_s=FLOAT, vx=FLOAT, vy=FLOAT)),
    # the simulator's people as they truly are, one list per attribute (agents/world/people.py); only
    # the human observer reads it, to perceive them with noise
    NodeSpec(NodeType.GROUND_TRUTH, (SIM_ROBOT,), _attrs(SIM_ROBOT, names=STRS, roles=STRS, x=FLOATS, y=FLOATS,
                                                         theta=FLOATS, vx=FLOATS, vy=FLOATS, groups=STRS,
                                                         stamp=FLOAT)),
    NodeSpec(NodeType.OBJECT, (RECOGNITION,), {
        **_attrs(RECOGNITION, kind=STR, forbidden_while_active=BOOL, footprint_shape=STR, footprint_dims=FLOATS,
                 interaction_shape=STR, interaction_dims=FLOATS),
        **_attrs(AGENDA_AGENT, R=FLOAT, R_band=INT, active=BOOL)}),
    NodeSpec(NodeType.ACTIVITY, (AGENDA_AGENT,), _attrs(AGENDA_AGENT, activity_id=STR, name=STR, object=STR, room=STR,
                                                        start_s=FLOAT, end_s=FLOAT, participants=STRS, state=STR,
                                                        source=STR)),
    NodeSpec(NodeType.AGENDA, (AGENDA_AGENT,), _attrs(AGENDA_AGENT, applied=STRS, changes=STRS)),
    NodeSpec(NodeType.AGENDA_REQUEST, (AGENDA_TOOL,), {
        **_attrs(AGENDA_TOOL, change=STR, requested_by=STR, requested_s=FLOAT),
        **_attrs(AGENDA_AGENT, state=STR, message=STR, answered_s=FLOAT)}),
    # the ROS bridge only creates missions (a /goal_pose, due now); the executive runs them
    NodeSpec(NodeType.MISSION, (EXECUTIVE, ROS_BRIDGE), {
        **_attrs(EXECUTIVE, started_s=FLOAT, finished_s=FLOAT, reason=STR, plan=STRS),
        **_attrs((EXECUTIVE, ROS_BRIDGE), mission_id=STR, goal=STR, time_s=FLOAT, state=STR, description=STR,
                 replans=INT)}),
    NodeSpec(NodeType.INTENTION, (EXECUTIVE,), {
        **_attrs(EXECUTIVE, kind=STR, goal_x=FLOAT, goal_y=FLOAT, goal_theta=FLOAT, goal_has_theta=BOOL,
                 until_s=FLOAT, target=STR, pass_through=BOOL, rooms=STRS, mission_id=STR, step=INT, rule=STR,
                 bindings=STRS, issued_s=FLOAT),
        **_attrs((EXECUTIVE, NAVIGATION), state=STR, reason=STR),
        **_attrs(NAVIGATION, replans=INT, path_x=FLOATS, path_y=FLOATS, path_cost=FLOAT, planned_s=FLOAT)}),
    NodeSpec(NodeType.SENSOR, (OBSERVER, RECOGNITION, AGENDA_AGENT), _attrs((OBSERVER, RECOGNITION, AGENDA_AGENT),
                                                                            observed_s=FLOAT)),
    # every agent's loop stamps its own (agents/runtime/heartbeat.py); the launcher watches them
    NodeSpec(NodeType.HEARTBEAT, (*ALL_AGENTS, ROS_BRIDGE), _attrs((*ALL_AGENTS, ROS_BRIDGE), beat=INT, pid=INT,
                                                                   wall_s=FLOAT)),
)}

_POSE = {"x": FLOAT, "y": FLOAT, "theta": FLOAT}

EDGES: tuple[EdgeSpec, ...] = (
    EdgeSpec(EdgeType.RT, (NodeType.WORLD,), (NodeType.ROOM, NodeType.ROBOT), (SIM_ROBOT,), _POSE),
    EdgeSpec(EdgeType.RT, (NodeType.WORLD,), (NodeType.ROBOT,), (ROS_BRIDGE,), _POSE),   # --robot ros
    EdgeSpec(EdgeType.RT, (NodeType.WORLD,), (NodeType.PERSON,), (OBSERVER,), _POSE),
    EdgeSpec(EdgeType.RT, (NodeType.WORLD,), (NodeType.OBJECT,), (RECOGNITION,), _POSE),
    EdgeSpec(EdgeType.IN, (NodeType.ROBOT,), (NodeType.ROOM,), (SIM_ROBOT,)),
    EdgeSpec(EdgeType.IN, (NodeType.PERSON,), (NodeType.ROOM,), (OBSERVER,)),
    EdgeSpec(EdgeType.IN, (NodeType.OBJECT,), (NodeType.ROOM,), (RECOGNITION,)),
    EdgeSpec(EdgeType.CONNECTED, (NodeType.ROOM,), (NodeType.ROOM,), (SIM_ROBOT,), {"door": STR, "doors": STRS}),
    EdgeSpec(EdgeType.INTERACTING, (NodeType.PERSON,), (NodeType.PERSON, NodeType.OBJECT), (OBSERVER,)),
    EdgeSpec(EdgeType.HAS, (NodeType.ACTIVITY,), (NodeType.OBJECT,), (AGENDA_AGENT,)),
    EdgeSpec(EdgeType.PARTICIPANT, (NodeType.PERSON,), (NodeType.ACTIVITY,), (AGENDA_AGENT,)),
    EdgeSpec(EdgeType.STEP_OF, (NodeType.INTENTION,), (NodeType.MISSION,), (EXECUTIVE,)),
)


class VocabularyError(ValueError):
    """A node that does not carry its type's attributes with their declared kinds."""


def _kind_ok(kind: str, value: Any) -> bool:
    if kind == BOOL:
        return isinstance(value, bool)
    if kind == INT:
        return isinstance(value, int) and not isinstance(value, bool)
    if kind == FLOAT:
        return isinstance(value, (int, float)) and not isinstance(value, bool)
    if kind == STR:
        return isinstance(value, str)
    if kind == FLOATS:
        return isinstance(value, list) and all(_kind_ok(FLOAT, v) for v in value)
    if kind == STRS:
        return isinstance(value, list) and all(isinstance(v, str) for v in value)
    return False


def check_attrs(node_type: str, attrs: Mapping[str, Any]) -> None:
    """VocabularyError naming the first attribute of ``attrs`` that is unknown for ``node_type`` or
    of the wrong kind (used where values are written, so a typo fails in the writer's own process)."""
    spec = NODES.get(node_type)
    if spec is None:
        raise VocabularyError(f"unknown node type {node_type!r}; known: {', '.join(sorted(NODES))}")
    for key, value in attrs.items():
        declared = spec.attrs.get(key)
        if declared is None:
            raise VocabularyError(f"a {node_type} node has no attribute {key!r}; "
                                  f"known: {', '.join(sorted(spec.attrs)) or 'none'}")
        if not _kind_ok(declared[0], value):
            raise VocabularyError(f"{node_type}.{key} must be {declared[0]}, got {value!r}")


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
                   str(_get(a, "mode", "idle")), bool(_get(a, "finished", False)))


def now_s(graph: Any) -> float | None:
    """The sim time the DSR's clock shows, or None before the simulator wrote it."""
    clock = ClockView.of(graph)
    return None if clock is None else clock.now_s


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
