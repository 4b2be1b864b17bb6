"""Mission strings: the one place that says what ``room:``, ``object:``, ``person:``, ``group:``,
``wait:`` and ``pose:`` mean before the grammar plans them.

Why here and not in the grammar: the grammar speaks of graph nodes only.  Two mission kinds need
the world model first: a ``pose:x,y,theta`` is planned as "be in the room of that point" followed
by driving to the point, and ``wait:ID`` names an agenda activity by the id `chronav agenda list`
shows, while its DSR node is ``activity/ID``.  The executive (live) and `chronav plan` (offline)
both turn a mission string into a grammar mission here, so they cannot read one differently.
"""

from __future__ import annotations

import math
import unicodedata
from dataclasses import dataclass

from agents.world.vocabulary import ACTIVITY_PREFIX, NodeType, activity_id_of, activity_name
from dsr.protocols import GraphReader
from scenes.names import shown

ROOM, OBJECT, PERSON, GROUP, WAIT, POSE = "room", "object", "person", "group", "wait", "pose"
KINDS = (ROOM, OBJECT, PERSON, GROUP, WAIT, POSE)
SYNTAX = ("room:NAME, object:NAME, person:NAME, group:P1+P2[+...], wait:ACTIVITY (the id `chronav agenda list` "
          "shows) or pose:X,Y[,THETA] (metres, radians)")
_NODE_TYPE = {ROOM: NodeType.ROOM, OBJECT: NodeType.OBJECT, PERSON: NodeType.PERSON, GROUP: NodeType.PERSON,
              WAIT: NodeType.ACTIVITY}
_LISTED = 12   # names listed in an error message, at most
# A mission names at most a group of people (names of at most 100 characters): a longer text is a
# mistake, refused before it is parsed and echoed (docs/limits.md).
MAX_MISSION_CHARS = 1_000
ECHO_CHARS = 80   # how much of a mission text an error message shows (scenes.names.shown)
_PLURAL: dict[str, str] = {NodeType.PERSON: "people"}


class MissionStringError(ValueError):
    """A mission string that is not one of the six forms (the message shows them)."""


@dataclass(frozen=True)
class MissionRequest:
    """A parsed mission string.

    ``names`` are DSR node names (a wait's is ``activity/<id>``); ``pose`` is set for ``pose:``."""

    text: str
    kind: str
    names: tuple[str, ...] = ()
    pose: tuple[float, float, float | None] | None = None

    def grammar_mission(self, room_of_pose: str | None = None) -> str:
        """The grammar's mission string (grammar/missions.py) for this request."""
        if self.kind == POSE:
            if room_of_pose is None:
                raise MissionStringError(f"{self.text!r}: the pose's room is needed")
            return f"{ROOM}:{room_of_pose}"
        return f"{self.kind}:{'+'.join(self.names)}"

    @property
    def node_type(self) -> str | None:
        return _NODE_TYPE.get(self.kind)


def parse_mission(text: str) -> MissionRequest:
    """``"wait:tv_game"`` -> MissionRequest(kind="wait", names=("activity/tv_game",)); MissionStringError
    (naming the accepted forms) for anything else.  The grammar's own forms are checked by the
    grammar's parser (grammar/missions.py), so both read them alike."""
    from grammar import MissionError
    from grammar import parse_mission as parse_grammar_mission

    if isinstance(text, str) and len(text) > MAX_MISSION_CHARS:
        raise MissionStringError(f"a mission of {len(text):,} characters ({shown(text, ECHO_CHARS)}); a mission "
                                 f"is at most {MAX_MISSION_CHARS:,}: {SYNTAX}")
    if isinstance(text, str):   # names are compared in NFC (scenes/names.py): "josé" typed either way
        text = unicodedata.normalize("NFC", text)
    if not isinstance(text, str) or ":" not in text:
        raise MissionStringError(f"mission {shown(text, ECHO_CHARS)!r} is not KIND:ARGUMENT; missions are "
                                 f"{SYNTAX}")
    kind, _, arg = (part.strip() for part in text.partition(":"))
    if kind not in KINDS:
        raise MissionStringError(f"unknown mission kind {shown(kind, 40)!r} in {shown(text, ECHO_CHARS)!r}; "
                                 f"expected one of {', '.join(KINDS)}")
    if not arg:
        raise MissionStringError(f"mission {shown(text, ECHO_CHARS)!r} has no argument; missions are {SYNTAX}")
    if kind == POSE:
        return MissionRequest(text, kind, (), _pose(text, arg))
    if kind == WAIT:
        activity = arg.removeprefix(ACTIVITY_PREFIX).strip()
        if not activity:
            raise MissionStringError(f"mission {shown(text, ECHO_CHARS)!r} names no activity")
        arg = activity_name(activity)
    try:
        parsed = parse_grammar_mission(f"{kind}:{arg}")
    except MissionError as exc:
        raise MissionStringError(str(exc).replace(f"{kind}:{arg}", text)) from None
    return MissionRequest(text, kind, parsed.names)


def _pose(text: str, arg: str) -> tuple[float, float, float | None]:
    parts = [p.strip() for p in arg.split(",")]
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if len(values) not in (2, 3) or not all(math.isfinite(v) for v in values):
        raise MissionStringError(f"bad pose mission {shown(text, ECHO_CHARS)!r}: expected pose:X,Y or "
                                 "pose:X,Y,THETA with finite "
                                 "numbers (metres, radians), e.g. pose:12.5,6.2,0")
    return (values[0], values[1], values[2] if len(values) == 3 else None)


def _listing(names: list[str]) -> str:
    listed = sorted(names)[:_LISTED]
    more = len(names) - len(listed)
    return ", ".join(listed) + (f" and {more} more" if more > 0 else "") if listed else "none"


def check_names(request: MissionRequest, graph: GraphReader) -> str | None:
    """Why the mission's names are not in the DSR ``graph``, in the user's words (listing what
    exists), or None."""
    node_type = request.node_type
    if node_type is None:
        return None
    for name in request.names:
        node = graph.get_node_by_name(name)
        if node is not None and node.type == node_type:
            continue
        known = [n.name for n in graph.nodes_of_type(node_type)]
        if request.kind == WAIT:
            return (f"no activity {shown(activity_id_of(name), 60)!r} on today's agenda; activities: "
                    f"{_listing([activity_id_of(k) for k in known])}")
        if node is not None:
            return f"{shown(name, 60)!r} is a {node.type}, not a {node_type}"
        return f"no {node_type} named {shown(name, 60)!r}; {_PLURAL.get(node_type, node_type + 's')}: {_listing(known)}"
    return None
