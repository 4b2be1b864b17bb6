"""Mission strings -> target patterns; the mission node added for the agenda rules."""

from __future__ import annotations

import pytest

from grammar.errors import MissionError
from grammar.missions import check_mission, parse_mission, with_mission_node
from grammar.world import graph_from_mapping


def links(text: str) -> set[tuple[str, str, str]]:
    return {(l.src, l.dst, l.label) for l in parse_mission(text).target.pattern.links}


def test_room_object_person_group_targets() -> None:
    assert links("room:kitchen") == {("robot", "kitchen", "in")}
    assert links("object:tv") == {("tv", "_room", "in"), ("robot", "_room", "in"), ("robot", "tv", "near")}
    assert ("robot", "ann", "facing") in links("person:ann") and ("robot", "ann", "near") in links("person:ann")
    group = links("group: ann + ben + cid")
    assert {("robot", p, "facing") for p in ("ann", "ben", "cid")} <= group
    assert {(p, "_room", "in") for p in ("ann", "ben", "cid")} <= group
    constants = {n.constant for n in parse_mission("group:ann+ben").target.pattern.nodes}
    assert constants == {None, "ann", "ben"}


def test_wait_target_is_an_attribute_condition() -> None:
    mission = parse_mission("wait:therapy")
    (node,) = mission.target.pattern.nodes
    assert node.constant == "therapy" and node.type == "activity" and node.conditions
    assert mission.node_type == "activity" and mission.names == ("therapy",)


def test_robot_can_be_pinned_by_name() -> None:
    nodes = {n.name: n.constant for n in parse_mission("room:kitchen", robot="r2d2").target.pattern.nodes}
    assert nodes == {"r2d2": "r2d2", "kitchen": "kitchen"}


@pytest.mark.parametrize("text,fragment", [
    ("kitchen", "not KIND:NAME"),
    ("fly:kitchen", "unknown mission kind 'fly'"),
    ("room:", "empty name"),
    ("group:ann", "at least two"),
    ("group:ann+", "empty name"),
    ("group:ann+ann", "twice"),
])
def test_malformed_missions(text: str, fragment: str) -> None:
    with pytest.raises(MissionError, match=fragment):
        parse_mission(text)


def test_check_mission_and_mission_node() -> None:
    graph = graph_from_mapping({"kitchen": {"type": "room"}, "tv": {"type": "object"},
                                "mission": {"type": "room"}}, [])
    assert check_mission(parse_mission("room:kitchen"), graph) is None
    assert check_mission(parse_mission("room:hall"), graph) == "no node named 'hall' in the world"
    assert check_mission(parse_mission("object:kitchen"), graph) == "'kitchen' is a room, not a object"
    with_node = with_mission_node(graph, parse_mission("object:tv"))
    assert "mission" not in with_node or with_node.nodes["mission"]["type"] == "room"  # never overwritten
    (key,) = [k for k, d in with_node.nodes(data=True) if d["type"] == "mission"]
    assert with_node.nodes[key]["goal"] == "object:tv"
    assert list(with_node.successors(key)) == ["tv"] and with_node.has_edge(key, "tv", key="targets")
    assert graph.number_of_nodes() == 3  # the input graph is not modified
