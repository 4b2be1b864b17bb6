"""Every walk over the formula and expression AST names each node class (``match`` with
``typing.assert_never``): a node class the walks do not know is refused loudly, never rendered
as its ``repr`` nor read as "reads nothing" (the silent fall-throughs issue 34 found)."""

from __future__ import annotations

import typing
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import pytest

from grammar import model
from grammar.formulas import FormulaEvaluator
from grammar.matcher import Matcher
from grammar.model import And, Expr, FAnd, FLink, Formula, Grammar, Literal, Pattern, PatternNode, Rule, Target
from grammar.planner import Planner
from grammar.relevance import condition_reads, relevant_rules
from grammar.render import expr_text, formula_text
from grammar.validate import check_expr, check_formula
from grammar.world import World, graph_from_mapping


@dataclass(frozen=True)
class FXor:
    """A formula class the grammar does not have (as if added to the model but not to a walk)."""

    items: tuple[Formula, ...]


@dataclass(frozen=True)
class Xor:
    items: tuple[Expr, ...]


ODD_FORMULA: Any = FAnd((FXor(()), FLink("in", "r", "x")))
ODD_EXPR: Any = And((Xor(()), Literal(True)))


def _rule(**parts: Any) -> Rule:
    return Rule("odd", Pattern((PatternNode("r", "robot"),)), Pattern((PatternNode("r", "robot"),)), **parts)


def _world() -> World:
    return World(graph_from_mapping({"robot": {"type": "robot"}}, []))


def _matcher() -> Matcher:
    return Matcher(model.TypeTable(), _world())


WALKS: dict[str, Callable[[], object]] = {
    "render formula": lambda: formula_text(ODD_FORMULA),
    "render expression": lambda: expr_text(ODD_EXPR),
    "validate formula": lambda: check_formula(ODD_FORMULA, frozenset({"r", "x"}), effect=False,
                                              in_condition=True, fallback=None),
    "validate expression": lambda: check_expr(ODD_EXPR, frozenset(), fallback=None),
    "formula children": lambda: list(map(model.formula_children, ODD_FORMULA.items)),
    "expression children": lambda: list(map(model.expr_children, ODD_EXPR.items)),
    "effect atoms": lambda: list(model.effect_atoms(ODD_FORMULA)),
    "relevance of a precondition": lambda: condition_reads(_rule(precondition=ODD_FORMULA)),
    "relevance of a where": lambda: condition_reads(_rule(where=(ODD_EXPR,))),
    "relevance of an effect": lambda: relevant_rules([_rule(effect=ODD_FORMULA)],
                                                     Target(Pattern((PatternNode("r", "robot"),)))),
    "condition truth": lambda: FormulaEvaluator(_matcher()).holds(ODD_FORMULA, _world().initial_state(), {}),
    "expression truth": lambda: _matcher().truth(ODD_EXPR, _world().initial_state(), {}),
    "expression value": lambda: _matcher().eval(Xor(()), _world().initial_state(), {}),
    "planning with the rule": lambda: Planner(Grammar("g", (_rule(precondition=ODD_FORMULA),)),
                                              _world()).plan(Target(Pattern((PatternNode("r", "person"),)))),
}


@pytest.mark.parametrize("walk", sorted(WALKS))
def test_an_unknown_node_class_is_refused_by_every_walk(walk: str) -> None:
    with pytest.raises(AssertionError, match="unreachable.*(FXor|Xor)"):
        WALKS[walk]()


@pytest.mark.parametrize("cls", typing.get_args(model.Formula) + typing.get_args(model.Expr))
def test_every_node_class_of_the_model_is_known_to_the_children_walk(cls: type) -> None:
    """The converse: each class of the unions is a case of the one place that lists them."""
    node = cls.__new__(cls)
    for name, value in {"items": (), "body": FAnd(()), "condition": FAnd(()), "then": FAnd(()),
                        "left": Literal(1), "right": Literal(2), "expr": Literal(3)}.items():
        if name in cls.__dataclass_fields__:
            object.__setattr__(node, name, value)
    children = model.formula_children(node) if cls in typing.get_args(model.Formula) else model.expr_children(node)
    assert isinstance(children, tuple)
