"""Applying a rule to a world state: the graph rewrite, its effect formula and ``set`` assignments.

Why separate from the planner: the executive will apply the same rewrite to predict what a plan
step should make true (to monitor it), without searching.

Order (PDDL semantics, documented in docs/grammar.md): every condition and every ``set`` value is
evaluated on the graph before the rule; then node creation, link removals (rewrite and effect),
node deletions, retypes, link additions (rewrite and effect), attribute assignments.
"""

from __future__ import annotations

from dataclasses import dataclass

from grammar.formulas import Changes, FormulaEvaluator
from grammar.matcher import Bindings, Matcher, NodeRef
from grammar.model import Rule
from grammar.world import State, StateEditor


@dataclass(frozen=True)
class Application:
    """The result of applying ``rule`` with ``bindings`` (LHS variables + created ones)."""

    rule: Rule
    bindings: dict[str, int]
    state: State


def apply_rule(rule: Rule, state: State, lhs_bindings: Bindings, matcher: Matcher,
               formulas: FormulaEvaluator) -> Application:
    """Rewrite ``state`` by ``rule`` at the match ``lhs_bindings`` (assumed to satisfy the rule)."""
    b = dict(lhs_bindings)
    editor = StateEditor(state)
    changes = Changes()
    for node in rule.created_nodes:
        b[node.name] = editor.create_node(node.type, node.name)
    changes.remove_edges.extend((b[l.src], b[l.dst], l.label) for l in rule.removed_links)
    changes.delete_nodes.extend(b[name] for name in rule.deleted_nodes)
    changes.retype.extend((b[n.name], n.type) for n in rule.retyped_nodes)
    changes.add_edges.extend((b[l.src], b[l.dst], l.label) for l in rule.added_links)
    if rule.effect is not None:
        formulas.apply_effect(rule.effect, state, b, changes, editor)
    values = []
    for assignment in rule.assignments:
        value = matcher.eval(assignment.value, state, b)
        if isinstance(value, NodeRef):  # `set a.owner = p` stores the node's name
            ref = value.node  # (a symbol this step creates is not in `state` yet: its new name)
            value = state.name_of(ref) if state.exists(ref) else editor.created[ref][1]
        values.append((b[assignment.var], assignment.attr, value))

    for s, d, label in changes.remove_edges:
        editor.remove_edge(s, d, label)
    deleted = set(changes.delete_nodes)
    for node_id in changes.delete_nodes:
        editor.delete_node(node_id, state)
    for node_id, node_type in changes.retype:
        if node_id not in deleted:
            editor.retype(node_id, node_type)
    for s, d, label in changes.add_edges:
        if s not in deleted and d not in deleted:
            editor.add_edge(s, d, label)
    for node_id, key, value in values:
        if node_id not in deleted:
            editor.set_attr(node_id, key, value)
    if rule.dormant or rule.activates:
        editor.activate(rule.activates)
    return Application(rule, b, editor.freeze())
