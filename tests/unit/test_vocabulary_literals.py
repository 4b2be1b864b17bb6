"""No bare node type, edge type or state string in agents/ or tools/: they name the vocabulary.

Why an AST scan: ``"pending"`` next to ``MissionState.PENDING`` is how a vocabulary stops being the
one definition (a renamed state keeps half its readers).  The scan looks where a type or a state is
meant, so words that merely look alike (a Rerun entity path "world", a CLI group "agenda") pass:

- the type argument of a graph call (``insert_node``, ``nodes_of_type``, ``insert_or_assign_edge``,
  ``edges_from`` ...);
- a comparison with something named like a type, state, kind or mode (``node.type ==``,
  ``attrs.get("state") !=``, ``mode ==``);
- the value of a ``"state"`` / ``"kind"`` / ``"type"`` / ``"mode"`` key in a dict literal, or of a
  ``state=`` / ``mode=`` keyword;
- a set or tuple of them bound to a name like ``*_STATES`` / ``*_TYPES`` / ``*_EDGES``.

The vocabulary itself (agents/world/vocabulary.py, agents/lib/states.py) is where they are spelt.
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

from agents.world.vocabulary import (ActivityState, ClockMode, EdgeType, IntentionKind, IntentionState, MissionState,
                                     NodeType, RequestState)
from tests.support import REPO_ROOT

SPELT = {Path("agents/world/vocabulary.py"), Path("agents/lib/states.py")}
WORDS = frozenset(str(v) for enum in (NodeType, EdgeType, MissionState, IntentionState, IntentionKind, ActivityState,
                                     RequestState, ClockMode) for v in enum)
#: graph calls and the position of their type argument
TYPE_ARGUMENT = {"insert_node": 0, "nodes_of_type": 0, "edges_of_type": 0, "insert_or_assign_edge": 2, "edges_from": 1,
                 "edges_to": 1, "get_edge": 2, "delete_edge": 2}
NAMED = ("type", "state", "kind", "mode")


def _text(node: ast.AST) -> str | None:
    return node.value if isinstance(node, ast.Constant) and isinstance(node.value, str) else None


def _names_a_state(node: ast.AST) -> bool:
    """``x.type``, ``state``, ``attrs["state"]``, ``attrs.get("kind", ...)``, ``self._last_mode`` ..."""
    if isinstance(node, ast.Attribute):
        return node.attr.lstrip("_").endswith(NAMED)
    if isinstance(node, ast.Name):
        return node.id.lstrip("_").endswith(NAMED)
    if isinstance(node, ast.Subscript):
        return _text(node.slice) in NAMED
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "get" and node.args:
        return _text(node.args[0]) in NAMED
    return False


def _items(node: ast.AST) -> list[ast.AST]:
    if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
        return list(node.elts)
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) \
            and node.func.id in ("frozenset", "set", "tuple") and node.args:
        return _items(node.args[0])
    return [node]


def literals(tree: ast.AST) -> Iterator[tuple[int, str, str]]:
    """(line, literal, where) of every type or state spelt out where the vocabulary is meant."""
    for node in ast.walk(tree):
        found: list[tuple[ast.AST, str]] = []
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr in TYPE_ARGUMENT:
            index = TYPE_ARGUMENT[node.func.attr]
            if len(node.args) > index:
                found.append((node.args[index], f"{node.func.attr}()"))
            found += [(kw.value, f"{node.func.attr}(type=)") for kw in node.keywords if kw.arg == "type"]
        if isinstance(node, ast.Call):
            found += [(kw.value, f"{kw.arg}=") for kw in node.keywords if kw.arg in ("state", "mode", "kind")]
        if isinstance(node, ast.Compare):
            parts = [node.left, *node.comparators]
            if any(_names_a_state(part) for part in parts):
                found += [(item, "comparison") for part in parts for item in _items(part)]
        if isinstance(node, ast.Dict):
            found += [(value, f"{_text(key)!r}: value") for key, value in zip(node.keys, node.values, strict=True)
                      if key is not None and _text(key) in NAMED]
        if isinstance(node, (ast.Assign, ast.AnnAssign)) and node.value is not None:
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            if any(isinstance(t, ast.Name) and t.id.endswith(("STATES", "TYPES", "EDGES")) for t in targets):
                found += [(item, "constant") for item in _items(node.value)]
        for value, where in found:
            text = _text(value)
            if text in WORDS:
                yield value.lineno, text, where


def scan(root: Path) -> list[str]:
    out = []
    for folder in ("agents", "tools"):
        for path in sorted((root / folder).rglob("*.py")):
            rel = path.relative_to(root)
            if rel in SPELT:
                continue
            out += [f"{rel}:{line}: {text!r} ({where})" for line, text, where in literals(ast.parse(path.read_text()))]
    return out


def test_agents_and_tools_name_types_and_states_through_the_vocabulary() -> None:
    found = scan(REPO_ROOT)
    assert found == [], ("bare type/state strings; use agents/world/vocabulary.py (NodeType, EdgeType, "
                         "MissionState ...):\n" + "\n".join(found))


def test_the_scan_finds_what_it_looks_for() -> None:
    source = '''
graph.insert_node("mission", "m", {"state": "pending"})
graph.insert_or_assign_edge(a, b, "RT", attrs={})
if node.type == "activity" and attrs.get("state") in ("running", "upcoming"): pass
if mode == "driving": pass
SHOWN_STATES = frozenset({"done"})
set_clock(mode="idle")
rr.log("world", x)                        # an entity path, not a node type
if row["name"] == "mission": pass          # a name, not a type
graph.insert_node(NodeType.MISSION, "m", {"state": MissionState.PENDING})
'''
    found = [(line, text) for line, text, _ in literals(ast.parse(source))]
    assert sorted(found) == [(2, "mission"), (2, "pending"), (3, "RT"), (4, "activity"), (4, "running"),
                             (4, "upcoming"), (5, "driving"), (6, "done"), (7, "idle")]
