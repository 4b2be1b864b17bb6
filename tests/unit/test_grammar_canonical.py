"""Worlds that differ only in the names of created symbols are one search state (issue 43).

The canonical key (grammar/canonical.py) must equate two worlds exactly when a renaming of their
created symbols (world symbols fixed) maps one onto the other: the same creations in another
order, interchangeable copies, and structures colour refinement alone cannot tell apart; and it
must keep apart worlds that only look alike (same counts, other links). Then the planner finds
the plans AGM finds with node-creating rules (tests/data/aggl/creating, built on the shape of
AGM's examples/egg grammar), and where the memory bound still stops a search, it says which
rules filled it.
"""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from grammar.canonical import canonical_key
from grammar.parser import parse_grammar, parse_target
from grammar.planner import NoPlan, Planner
from grammar.world import State, StateEditor, World, graph_from_mapping
from tests.support import REPO_ROOT
from tools.cli import app

DATA = REPO_ROOT / "tests" / "data" / "aggl" / "creating"
runner = CliRunner()

TWO_ROOMS = graph_from_mapping({"hall": {"type": "room"}, "kitchen": {"type": "room"}}, [])
PUT_BOX = "rule put { lhs { r:room } rhs { r:room  b:box  t:tag  b->r(in)  t->b(on) } }"


def _apply(planner: Planner, state: State, room: str) -> State:
    """The state after ``put`` on ``room``."""
    for _rule, bindings, nxt in planner.applications(state):
        if state.name_of(bindings["r"]) == room:
            return nxt
    raise AssertionError(f"put does not apply to {room}")


def _after(planner: Planner, rooms: list[str]) -> State:
    state = planner.world.initial_state()
    for room in rooms:
        state = _apply(planner, state, room)
    return state


def test_the_same_creations_in_another_order_are_one_state() -> None:
    planner = Planner(parse_grammar(PUT_BOX, "put.aggl"), TWO_ROOMS)
    a = _after(planner, ["hall", "kitchen", "hall"])
    b = _after(planner, ["kitchen", "hall", "hall"])
    c = _after(planner, ["hall", "hall", "kitchen"])
    assert a != b and a != c  # the overlays name the created symbols differently...
    assert canonical_key(a) == canonical_key(b) == canonical_key(c)  # ...but they are one world


def test_worlds_that_only_look_alike_stay_apart() -> None:
    planner = Planner(parse_grammar(PUT_BOX, "put.aggl"), TWO_ROOMS)
    two_in_hall = _after(planner, ["hall", "hall"])
    one_each = _after(planner, ["hall", "kitchen"])
    one = _after(planner, ["hall"])
    assert len({canonical_key(two_in_hall), canonical_key(one_each), canonical_key(one)}) == 3
    # a world symbol keeps its identity: a box in the hall is not a box in the kitchen
    assert canonical_key(_after(planner, ["hall"])) != canonical_key(_after(planner, ["kitchen"]))


def _ring(world: World, cycles: list[list[int]]) -> State:
    """A state whose created symbols (all of one type, one label) form the given cycles, the
    symbols created in the order of ``cycles`` flattened (positions index creation order)."""
    editor = StateEditor(world.initial_state())
    count = sum(len(c) for c in cycles)
    ids = [editor.create_node("n", "v") for _ in range(count)]
    for cycle in cycles:
        for i, j in zip(cycle, cycle[1:] + cycle[:1], strict=True):
            editor.add_edge(ids[i], ids[j], "next")
    return editor.freeze()


def test_structures_colour_refinement_cannot_split_are_told_apart_and_matched() -> None:
    """Two directed triangles and one directed hexagon: every created symbol has one link in and
    one out, so colour refinement leaves all six tied; singling them out decides."""
    world = World(graph_from_mapping({"hall": {"type": "room"}}, []))
    triangles = _ring(world, [[0, 1, 2], [3, 4, 5]])
    hexagon = _ring(world, [[0, 1, 2, 3, 4, 5]])
    hexagon_renamed = _ring(world, [[3, 0, 5, 1, 4, 2]])
    triangles_renamed = _ring(world, [[5, 0, 3], [1, 4, 2]])
    assert hexagon != hexagon_renamed and triangles != triangles_renamed
    assert canonical_key(hexagon) == canonical_key(hexagon_renamed)
    assert canonical_key(triangles) == canonical_key(triangles_renamed)
    assert canonical_key(triangles) != canonical_key(hexagon)


def test_an_attribute_naming_a_created_symbol_follows_the_renaming() -> None:
    grammar = parse_grammar("rule put { lhs { r:room } rhs { r:room  b:box  b->r(in) } set r.last = b }", "p.aggl")
    planner = Planner(grammar, TWO_ROOMS)
    a = _after(planner, ["hall", "kitchen"])
    b = _after(planner, ["kitchen", "hall"])
    assert canonical_key(a) == canonical_key(b)
    assert canonical_key(_after(planner, ["hall", "hall"])) != canonical_key(a)


@pytest.mark.slow  # about 5 s of planning
def test_the_egg_like_kitchen_plan_is_found_within_agm_s_world_growth_bound() -> None:
    """Regression (issue 43): with rules that create symbols at every step (findEgg, clutter,
    clutter2, as AGM's encuentraHuevo, estorbo, estorbo2), chronav stopped at its 1,000,000-fact
    memory bound after 3,608 expansions. Keyed up to renaming and bounded as AGM bounds world
    growth, the 6-step plan is found in about 1,100 expansions."""
    result = runner.invoke(app, ["plan", "--world", str(DATA / "kitchen_world.xml"),
                                 "--target", str(DATA / "fried_egg_on_plate.aggt"),
                                 "--grammar", str(DATA / "kitchen.aggl"), "--json"])
    assert result.exit_code == 0, result.output
    payload = json.loads(result.stdout)
    assert payload["found"] and payload["cost"] == 6 and payload["max_new_symbols"] == 5
    assert [s["rule"] for s in payload["steps"]] == ["lightStove", "findEgg", "move", "heat", "fry", "move"]
    assert payload["expanded"] < 3_000
    # findEgg creates e and es; AGM numbers them after the world's largest id, 8
    assert payload["agm_plan"][1].startswith("findEgg@") and "'e': '" in payload["agm_plan"][1]


def test_an_explicit_world_growth_bound_too_small_for_the_plan_says_so() -> None:
    result = runner.invoke(app, ["plan", "--world", str(DATA / "kitchen_world.xml"),
                                 "--target", str(DATA / "fried_egg_on_plate.aggt"),
                                 "--grammar", str(DATA / "kitchen.aggl"), "--max-new-symbols", "1", "--json"])
    assert result.exit_code == 1
    payload = json.loads(result.stdout)
    assert not payload["found"] and "at most 1 symbols larger than the start" in payload["reason"]


def test_the_memory_bound_message_counts_the_worlds_each_rule_made() -> None:
    grammar = parse_grammar(PUT_BOX + "\nrule paint { lhs { t:tag } rhs { t:tag  t->t(red) } }", "put.aggl")
    target = parse_target("target { r:room  b:box  b->r(in)  b->b(shiny) }", "t.aggt")
    result = Planner(grammar, TWO_ROOMS).plan(target, max_state_size=1_500, prune=False)
    assert isinstance(result, NoPlan) and "memory bound" in result.reason
    assert "the kept worlds were made by " in result.reason
    assert "put (" in result.reason and "paint (" in result.reason and " worlds, " in result.reason


@pytest.mark.slow  # about 5 s of planning
def test_interchangeable_spotted_things_are_searched_once() -> None:
    """Regression (issue 43: AGM's clean_table_easy target3, a 6-step plan, stopped chronav at the
    memory bound after 1,128 expansions). The same shape, written for the tests: each ``spot``
    creates a thing with seven symbols, each ``shareDesk`` eight more; keyed by creation order the
    search stopped after 1,128 expansions, keyed up to renaming it finds the plan in about 330."""
    result = runner.invoke(app, ["plan", "--world", str(DATA / "inventory_world.xml"),
                                 "--target", str(DATA / "two_items_shared.aggt"),
                                 "--grammar", str(DATA / "inventory.aggl"), "--json"])
    assert result.exit_code == 0, result.output
    payload = json.loads(result.stdout)
    assert payload["found"] and payload["cost"] == 6
    assert sorted(s["rule"] for s in payload["steps"]) == ["identifyDesk"] * 2 + ["shareDesk"] * 2 + ["spot"] * 2
    assert payload["expanded"] < 1_128
