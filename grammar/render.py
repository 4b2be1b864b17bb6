"""Model objects back to text: conditions, patterns and formulas as a person would write them.

Why: a diagnosis ("this rule is blocked by this condition") must quote the condition in the
grammar's own words; the model keeps positions but not the source text, and a condition may be
a piece of a larger ``where``. The text is the native dialect's for expressions and patterns and
AGM's prefix form for formulas; it is for reading, not guaranteed to re-parse byte for byte.
"""

from __future__ import annotations

from typing import assert_never

from grammar.model import (
    And,
    AttrRef,
    Compare,
    Exists,
    Expr,
    FAnd,
    FCreate,
    FDelete,
    FExists,
    FForall,
    FLink,
    FNot,
    FOr,
    Formula,
    FRetype,
    FSame,
    FWhen,
    ListLit,
    Literal,
    Not,
    Or,
    Pattern,
    PatternLink,
    PatternNode,
    VarRef,
)

MAX_TEXT = 300


def _cut(text: str) -> str:
    return text if len(text) <= MAX_TEXT else text[:MAX_TEXT - 1] + "…"


def value_text(value: object) -> str:
    """An attribute value as written in a condition: strings quoted, ``true``/``false``/``none``."""
    if value is None:
        return "none"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return '"' + value.replace('"', '\\"') + '"'
    if isinstance(value, tuple):
        return "[" + ", ".join(value_text(v) for v in value) + "]"
    return repr(value)


def expr_text(expr: Expr) -> str:
    return _cut(_expr(expr, top=True))


def _expr(expr: Expr, top: bool = False) -> str:
    match expr:
        case Literal():
            return value_text(expr.value)
        case ListLit():
            return "[" + ", ".join(_expr(e) for e in expr.items) + "]"
        case AttrRef():
            return expr.attr if expr.var is None else f"{expr.var}.{expr.attr}"
        case VarRef():
            return expr.var
        case Compare():
            return f"{_expr(expr.left)} {expr.op} {_expr(expr.right)}"
        case Not(expr=Exists() as inner):
            return "not " + _expr(inner)
        case Not(expr=AttrRef() | VarRef() | Literal() as inner):
            return "not " + _expr(inner)
        case Not():
            return f"not ({_expr(expr.expr)})"
        case And() | Or():
            word = " and " if isinstance(expr, And) else " or "
            text = word.join(_expr(e) for e in expr.items)
            return text if top else f"({text})"
        case Exists():
            return "exists { " + pattern_text(expr.pattern) + " }"
        case _:
            assert_never(expr)


def node_text(node: PatternNode) -> str:
    name = f'"{node.constant}"' if node.constant is not None and node.constant != node.name else node.name
    conds = f" [{', '.join(_expr(c, top=True) for c in node.conditions)}]" if node.conditions else ""
    return f"{name}:{node.type}{conds}"


def link_text(link: PatternLink) -> str:
    arrow = "--" if link.undirected else "->"
    conds = f" [{', '.join(_expr(c, top=True) for c in link.conditions)}]" if link.conditions else ""
    star = "*" if link.negated else ""
    return f"{link.src}{arrow}{link.dst}({link.label}){star}{conds}"


def pattern_text(pattern: Pattern) -> str:
    return _cut("  ".join([node_text(n) for n in pattern.nodes] + [link_text(l) for l in pattern.links]))


def formula_text(formula: Formula) -> str:
    return _cut(_formula(formula))


def _formula(f: Formula) -> str:
    match f:
        case FLink():
            return f"({f.label} {f.src} {f.dst})"
        case FSame():
            return f"(= {f.a} {f.b})"
        case FNot():
            return f"(not {_formula(f.body)})"
        case FAnd():
            return "(and " + " ".join(_formula(i) for i in f.items) + ")"
        case FOr():
            return "(or " + " ".join(_formula(i) for i in f.items) + ")"
        case FExists() | FForall():
            word = "exists" if isinstance(f, FExists) else "forall"
            decls = " ".join(f"{v.name}:{v.type}" for v in f.vars)
            return f"({word} {decls} {_formula(f.body)})"
        case FWhen():
            return f"(when {_formula(f.condition)} {_formula(f.then)})"
        case FCreate():
            return f"(create {f.var} {f.type})"
        case FDelete():
            return f"(delete {f.var})"
        case FRetype():
            return f"(retype {f.var} {f.type})"
        case _:
            assert_never(f)
