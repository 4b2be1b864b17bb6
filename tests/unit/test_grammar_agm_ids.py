"""Plan files whose symbol ids are the ones AGM's planner assigns, checked as AGM's
``AGGLPlanChecker`` checks them.

The checker below is written here from AGM's own code, not from chronav's planner:
``AGGLPlanChecker.run`` applies each plan line with the rule's ``_trigger(world, params,
checked=False)`` that ``generateAGGLPlannerCode.py`` generates: the left-hand side's symbols must
exist with the rule's types, be distinct and have the rule's links (and not its ``*`` links); the
right-hand side's new symbols are created one by one with ``getNewIdForSymbol`` (largest id of the
graph + 1) in the iteration order of ``AGMGraph.getNodeChanges``'s Python 2 dict; deleted symbols
are removed with their links, then the links only on the left are removed and those only on the
right added. The target is then matched like ``generateTarget_AGGT``'s code (constants are ids).
"""

from __future__ import annotations

import ast
import itertools
import json
import re
import xml.etree.ElementTree as ET
from pathlib import Path

from typer.testing import CliRunner

from grammar.agm_order import agm_creation_order, py2_dict_order
from grammar.parser import load_grammar, load_target
from tests.support import REPO_ROOT
from tools.cli import app

DATA = REPO_ROOT / "tests" / "data" / "aggl"
runner = CliRunner()


# ----------------------------------------------------------------------------- Python 2 dicts
def _py2_hash(s: str) -> int:
    """``string_hash`` of CPython 2.7 (Objects/stringobject.c), 64-bit, no randomisation."""
    x = ord(s[0]) << 7
    for c in s:
        x = ((1000003 * x) & 0xFFFFFFFFFFFFFFFF) ^ ord(c)
    return x ^ len(s)  # kept unsigned: only its low bits and its unsigned value are used below


def _py2_keys(table_size: int, keys: list[str]) -> tuple[list[str], int]:
    """Insert ``keys`` (in order) into a CPython 2.7 dict table of ``table_size`` slots, growing it
    as ``PyDict_SetItem``/``dictresize`` do; return the keys in slot order and the final size."""
    table: list[str | None] = [None] * table_size
    for count, key in enumerate(keys, 1):
        h = _py2_hash(key)
        i, perturb = h % len(table), h
        while table[i] is not None:
            i = (5 * i + perturb + 1) % len(table)
            perturb >>= 5
        table[i] = key
        if count * 3 >= len(table) * 2:  # two thirds full: resize to > 4x the entries
            size = 8
            while size <= 4 * count:
                size *= 2
            return _py2_keys(size, [k for k in table if k is not None] + list(keys[count:]))
    return [k for k in table if k is not None], len(table)


def agm_creation_order_from_agm(rhs_in_file_order: list[str], lhs: set[str]) -> list[str]:
    """``for name in R.keys(): if not name in L.keys(): toCreate.append(...)`` where R =
    dict(rhs.nodes) of the parsed graph (AGM's generator does not deep-copy it first)."""
    copied, _ = _py2_keys(8, rhs_in_file_order)
    presized = 8
    while presized <= 2 * len(copied) and len(copied) * 3 >= 16:  # dict(d): one resize up front
        presized *= 2
    merged = _py2_keys_no_resize(presized, copied)
    return [name for name in merged if name not in lhs]


def _py2_keys_no_resize(size: int, keys: list[str]) -> list[str]:
    table: list[str | None] = [None] * size
    for key in keys:
        h = _py2_hash(key)
        i, perturb = h % size, h
        while table[i] is not None:
            i = (5 * i + perturb + 1) % size
            perturb >>= 5
        table[i] = key
    return [k for k in table if k is not None]


# ----------------------------------------------------------------------------- AGM's plan checker
class WrongRuleExecution(Exception):
    pass


def read_world(path: Path) -> tuple[dict[str, str], set[tuple[str, str, str]]]:
    root = ET.parse(path).getroot()
    symbols = {s.get("id"): s.get("type") for s in root.iter("symbol")}
    links = {(l.get("src"), l.get("dst"), l.get("label")) for l in root.iter("link")}
    return symbols, links  # type: ignore[return-value]


def apply_action(rules: dict, nodes: dict[str, str], links: set, name: str, params: dict[str, str]) -> None:
    rule = rules[name]
    lhs = {n.name: n.type for n in rule.lhs.nodes}
    rhs = {n.name: n.type for n in rule.rhs.nodes}
    for var, value in params.items():  # AGGLPlanChecker.run: unknown ids only for new symbols
        if value not in nodes and var not in rhs:
            raise WrongRuleExecution(f"parameter {value!r} ({var!r}) not in the world")
    n2id = {var: params[var] for var in lhs}
    if len(set(n2id.values())) != len(n2id):
        raise WrongRuleExecution(f"{name}: two variables on one symbol")
    for var, symbol_type in lhs.items():
        if nodes.get(n2id[var]) != symbol_type:
            raise WrongRuleExecution(f"{name}: {var}={n2id[var]} is not a {symbol_type}")
    for link in rule.lhs.links:
        present = (n2id[link.src], n2id[link.dst], link.label) in links
        if present == link.negated:
            raise WrongRuleExecution(f"{name}: link {link.src}->{link.dst}({link.label}) test fails")
    smap = dict(n2id)
    for var in agm_creation_order_from_agm([n.name for n in rule.rhs.nodes], set(lhs)):
        new_id = 1                                          # getNewIdForSymbol
        for k in nodes:
            if int(k) >= new_id:
                new_id = int(k) + 1
        smap[var] = str(new_id)
        nodes[str(new_id)] = rhs[var]
    for var in lhs:
        if var in rhs and rhs[var] != lhs[var]:
            nodes[smap[var]] = rhs[var]
    for var in lhs:
        if var not in rhs:
            del nodes[smap[var]]
            links -= {l for l in links if smap[var] in (l[0], l[1])}
    left = {(l.src, l.dst, l.label) for l in rule.lhs.links if not l.negated}
    right = {(l.src, l.dst, l.label) for l in rule.rhs.links if not l.negated}
    for src, dst, label in left - right:
        links.discard((smap[src], smap[dst], label))
    for src, dst, label in right - left:
        links.add((smap[src], smap[dst], label))


def target_achieved(target, nodes: dict[str, str], links: set) -> bool:
    names = [n.name for n in target.pattern.nodes]
    types = {n.name: n.type for n in target.pattern.nodes}
    for candidate in itertools.permutations(nodes, len(names)):
        m = dict(zip(names, candidate))
        if any(v[0].isdigit() and m[v] != v for v in names) or any(nodes[m[v]] != types[v] for v in names):
            continue
        if all(((m[l.src], m[l.dst], l.label) in links) != l.negated for l in target.pattern.links):
            return True
    return False


def check_plan(grammar: Path, world: Path, plan_lines: list[str], target: Path) -> bool:
    """AGGLPlanChecker: True when every action applies and the target is reached."""
    rules = {r.name: r for r in load_grammar(grammar).rules}
    nodes, links = read_world(world)
    try:
        for line in plan_lines:
            match = re.fullmatch(r"(\w+)@(\{.*\})", line.strip())
            assert match, line
            apply_action(rules, nodes, links, match.group(1), ast.literal_eval(match.group(2)))
    except WrongRuleExecution:
        return False
    return target_achieved(load_target(target), nodes, links)


# ----------------------------------------------------------------------------- tests
def test_the_python2_dict_order_matches_planner_code_agm_generated() -> None:
    """Orders read off two planner modules AGM generated (rules named findObjectVisually)."""
    assert agm_creation_order(["r", "cl", "o", "re", "t", "rb", "po", "se"], ["r"]) == \
        ("cl", "o", "re", "t", "rb", "po", "se")
    assert agm_creation_order(["r", "re", "se", "cl", "po", "o"], ["r"]) == ("re", "se", "cl", "po", "o")
    # the transcription in this test agrees on them, and on every order of declaration
    for names in (["r", "cl", "o", "re", "t", "rb", "po", "se"], ["r", "re", "se", "cl", "po", "o"],
                  ["robot", "room", "obj", "status", "pose", "colour", "a", "b", "c"]):
        for order in itertools.islice(itertools.permutations(names), 50):
            assert list(agm_creation_order(list(order), ["r", "robot", "room"])) == \
                agm_creation_order_from_agm(list(order), {"r", "robot", "room"})
    # parameters (``dict(nodes, **parameters)``) are neither created nor numbered
    assert "p" in py2_dict_order(["r", "o"], ["p"]) and agm_creation_order(["r", "o"], ["r"], ["p"]) == ("o",)


def test_two_symbols_created_by_one_step_get_agms_ids_and_agms_checker_accepts_the_plan() -> None:
    grammar, world, target = DATA / "create_two.aggl", DATA / "create_world.xml", DATA / "hold_object.aggt"
    assert agm_creation_order_from_agm(["r", "rm", "o", "s"], {"r", "rm"}) == ["s", "o"]  # not file order
    result = runner.invoke(app, ["plan", "--world", str(world), "--target", str(target),
                                 "--grammar", str(grammar), "--json"])
    assert result.exit_code == 0, result.output
    lines = json.loads(result.stdout)["agm_plan"]
    assert [line.split("@")[0] for line in lines] == ["tidy", "findObject", "grasp"]
    assert check_plan(grammar, world, lines, target)
    # the plain output prints the same lines
    text = runner.invoke(app, ["plan", "--world", str(world), "--target", str(target), "--grammar", str(grammar)])
    assert [line.strip() for line in text.stdout.splitlines()[-3:]] == lines
    # the checker is not a rubber stamp: ids in file order, or counted from the world's largest
    # id before tidy deleted symbol 3, are refused
    find = ast.literal_eval(lines[1].split("@", 1)[1])
    swapped = [lines[0], lines[1].replace(f"'o': '{find['o']}'", f"'o': '{find['s']}'"),
               lines[2].replace(f"'o': '{find['o']}'", f"'o': '{find['s']}'").replace(
                   f"'s': '{find['s']}'", f"'s': '{find['o']}'")]
    assert not check_plan(grammar, world, swapped, target)
    shifted = [lines[0], lines[1], re.sub(r"'(o|s)': '(\d+)'", lambda m: f"'{m[1]}': '{int(m[2]) + 1}'", lines[2])]
    assert not check_plan(grammar, world, shifted, target)


# ----------------------------------------------------------------------------- issue 43
def test_symbols_created_in_one_step_are_numbered_as_agms_current_generator_numbers_them() -> None:
    """Regression (issue 43): AGM's generator builds ``dict(rhs.nodes)`` from the parsed grammar,
    with no deep copy in between. With one, chronav numbered clean_table_easy's
    ``tellHumanAboutTable`` symbols rb = 16, hs = 17 where AGM's plan has hs = 16, rb = 17."""
    lhs = ["c", "h", "m", "o", "p", "r", "sr"]
    current = ["c", "ch", "oh", "hr", "h", "m", "mh", "o", "p", "sh", "hs", "rb", "sr", "ph", "r"]
    assert agm_creation_order(current, lhs) == ("ch", "oh", "hr", "mh", "sh", "hs", "rb", "ph")  # AGM's plan
    # the module AGM's current generator wrote for that grammar's earlier version creates rb first
    earlier = ["c", "ch", "oh", "hr", "h", "m", "mh", "o", "p", "sr", "sh", "rb", "hs", "ph", "r"]
    assert agm_creation_order(earlier, lhs) == ("ch", "oh", "hr", "mh", "sh", "rb", "hs", "ph")
    result = runner.invoke(app, ["plan", "--world", str(DATA / "tell_human_world.xml"),
                                 "--target", str(DATA / "human_knows_object.aggt"),
                                 "--grammar", str(DATA / "tell_human.aggl"), "--json"])
    assert result.exit_code == 0, result.output
    line = json.loads(result.stdout)["agm_plan"][0]
    ids = ast.literal_eval(line.split("@", 1)[1])
    assert (ids["ch"], ids["oh"], ids["hr"], ids["mh"], ids["sh"], ids["hs"], ids["rb"], ids["ph"]) == \
        ("11", "12", "13", "14", "15", "16", "17", "18")
    assert check_plan(DATA / "tell_human.aggl", DATA / "tell_human_world.xml", [line],
                      DATA / "human_knows_object.aggt")


def _shipped_agm_grammars() -> list[Path]:
    """Every grammar chronav ships or tests against (the shared corpus of real AGM files when present)."""
    return [*sorted(DATA.rglob("*.aggl")), REPO_ROOT / "grammar" / "social_navigation.aggl",
            *sorted((REPO_ROOT.parent / "shared" / "corpus" / "aggl").glob("*.aggl"))]


def test_every_shipped_rule_creating_several_symbols_numbers_them_in_agms_order() -> None:
    """Each rule of the shipped AGM grammars that creates more than one symbol: chronav's order is
    the one the transcription of AGM's dict (above, written from AGM's code) gives."""
    checked = []
    for path in _shipped_agm_grammars():
        try:
            grammar = load_grammar(path)
        except Exception:  # noqa: BLE001 - a file for an error-path test; not a grammar to check
            continue
        for rule in grammar.rules:
            if len(rule.created_nodes) > 1:
                lhs = {n.name for n in rule.lhs.nodes}
                assert list(rule.agm_creation_order) == \
                    agm_creation_order_from_agm([n.name for n in rule.rhs.nodes], lhs), (path, rule.name)
                checked.append(rule.name)
    assert {"findObject", "tell", "clutter", "clutter2", "findEgg"} <= set(checked)


def _plan_json(grammar: Path, world: Path, target: Path, *extra: str) -> dict:
    result = runner.invoke(app, ["plan", "--world", str(world), "--target", str(target),
                                 "--grammar", str(grammar), "--json", *extra])
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout)


def test_expand_prints_the_primitive_plan_agms_executive_runs() -> None:
    """Regression (issue 43): for a target whose plan is two hierarchical steps (as the egg
    grammar's p1: *freirJerarquico, *enfriarJerarquico), ``--expand`` prints the primitive actions
    AGM's executive runs, one AGM plan line each; AGM's plan checker accepts them in order."""
    grammar, world, target = DATA / "cook_hierarchical.aggl", DATA / "cook_world.xml", DATA / "fried_cold_egg.aggt"
    payload = _plan_json(grammar, world, target, "--expand")
    assert [s["rule"] for s in payload["steps"]] == ["fryH", "coolH"]
    lines = payload["primitive_plan"]["agm_plan"]
    assert [line.split("@")[0] for line in lines] == ["move", "lightFire", "heat", "fry", "move", "startFridge",
                                                      "cool"]
    assert check_plan(grammar, world, lines, target)
    # the second move starts where the first left the egg (on the fire, 5), which splicing the
    # expansions of the abstract plan gets wrong: its coolH was expanded from the world before fryH
    assert ast.literal_eval(lines[4].split("@", 1)[1])["c1"] == "5"
    spliced = [step for top in payload["steps"] for step in top["expansion"]]
    assert spliced[4]["agm_bindings"]["c1"] == "3"
    # the text output lists the same lines after the AGM plan
    text = runner.invoke(app, ["plan", "--world", str(world), "--target", str(target), "--grammar", str(grammar),
                               "--expand"]).stdout.splitlines()
    at = next(i for i, line in enumerate(text) if line.startswith("primitive plan (AGM's executive: 7 step(s)"))
    assert [line.strip() for line in text[at + 1:]] == lines


def test_expand_carries_the_ids_of_created_symbols_from_one_replan_to_the_next() -> None:
    grammar, world, target = DATA / "create_two.aggl", DATA / "create_world.xml", DATA / "hold_object.aggt"
    payload = _plan_json(grammar, world, target, "--expand")
    lines = payload["primitive_plan"]["agm_plan"]
    assert lines == payload["agm_plan"]  # no hierarchical step: the executive runs the plan as it is
    assert check_plan(grammar, world, lines, target)


def test_expand_is_refused_without_world_and_target() -> None:
    result = runner.invoke(app, ["plan", str(DATA / "two_rooms.xml"), "--mission", "room:kitchen", "--expand"])
    assert result.exit_code == 2 and "--expand goes with --world" in result.output
