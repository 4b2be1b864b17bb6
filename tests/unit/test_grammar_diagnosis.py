"""The structured no-plan diagnosis (grammar/diagnosis.py) the executive logs: the rule, the
bindings, the failing condition with its source position, the facts and the witness nodes."""

from __future__ import annotations

from grammar import parse_grammar, parse_target, plan
from grammar.planner import NoPlan
from grammar.world import graph_from_mapping


def no_plan(result: object) -> NoPlan:
    assert isinstance(result, NoPlan), result
    assert result.diagnosis is not None
    return result


def test_attribute_condition_names_the_node_and_its_value() -> None:
    g = parse_grammar('''
        rule enter {
            lhs { r:robot a:room b:room d:door  r->a(in)  a->b(door) [door == d.name] }
            rhs { r:robot a:room b:room d:door  r->b(in)  a->b(door) }
            where d.open != false
        }
    ''', "doors.aggl")
    world = graph_from_mapping({"robot": {"type": "robot"}, "hall": {"type": "room"}, "attic": {"type": "room"},
                                "trapdoor": {"type": "door", "open": False}},
                               [("robot", "hall", "in"), ("hall", "attic", "door", {"door": "trapdoor"})])
    result = no_plan(plan(g, world, parse_target('target { "robot":robot "attic":room robot->attic(in) }')))
    d = result.diagnosis
    assert d is not None and d.unmet == ("robot -in-> attic",)
    blocker = d.blockers[0]
    assert (blocker.rule, blocker.condition) == ("enter", "where d.open != false")
    assert (blocker.pos.file, blocker.pos.line) == ("doors.aggl", 5)  # type: ignore[union-attr]
    assert blocker.focus == {"r": "robot", "b": "attic"} and blocker.bindings["d"] == "trapdoor"
    assert blocker.facts == ('trapdoor.open = false',)
    assert [(w.var, w.node, dict(w.attrs)) for w in blocker.witnesses] == [("d", "trapdoor", {"open": False})]
    assert "blocked: enter(r=robot, b=attic): where d.open != false (doors.aggl:5:19) fails: trapdoor.open = false" \
        in result.reason


def test_agm_forall_precondition_names_the_counterexample() -> None:
    g = parse_grammar('''name=x
===
changeRoom : active(1)
{
	{
		robot:robot
		a:room
		b:room
		robot->a(in)
	}
	=>
	{
		robot:robot
		a:room
		b:room
		robot->b(in)
	}
	precondition
	{
		(forall p:person (not (is_blocking p robot)))
	}
}
''', "agm.aggl")
    world = graph_from_mapping({"1": {"type": "robot"}, "2": {"type": "room"}, "3": {"type": "room"},
                                "4": {"type": "person"}},
                               [("1", "2", "in"), ("4", "1", "is_blocking")])
    d = no_plan(plan(g, world, parse_target('{ 1:robot 3:room 1->3(in) }', "t.aggt"))).diagnosis
    assert d is not None
    blocker = d.blockers[0]
    assert blocker.condition == "precondition (forall p:person (not (is_blocking p robot)))"
    assert blocker.facts == ("4 -is_blocking-> 1",)
    assert blocker.focus == {"robot": "1", "b": "3"}
    assert [w.node for w in blocker.witnesses] == ["4"]
    assert blocker.to_dict()["pos"] == {"file": "agm.aggl", "line": 20, "column": 26}


def test_no_rule_for_a_goal_and_a_dormant_rule_are_said() -> None:
    g = parse_grammar('''
        rule open dormant { lhs { d:door } rhs { d:door  d->d(opened) } }
        rule paint { lhs { d:door } rhs { d:door  d->d(painted) } }
    ''', "dormant.aggl")
    world = graph_from_mapping({"door": {"type": "door"}}, [])
    d = no_plan(plan(g, world, parse_target('target { "door":door  door->door(opened) }'))).diagnosis
    assert d is not None and d.blockers[0].condition == "dormant"
    d = no_plan(plan(g, world, parse_target('target { "door":door  door->door(locked) }'))).diagnosis
    assert d is not None and d.notes == ("no rule can make 'door -locked-> door' true",)
