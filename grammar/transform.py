"""Lark parse tree -> typed model (grammar/model.py), for both dialects.

Why a separate module from parser.py: this is the only place that knows the shape of the lark
tree (rule and terminal names of aggl.lark); parser.py deals with files, includes and errors.
Only local, syntactic decisions are made here; cross-references are checked in validate.py.
"""

from __future__ import annotations

import re
from typing import Any, assert_never

from lark import Token, Transformer, v_args

from grammar.errors import GrammarError, GrammarWarning, SourcePos, shorten
from grammar.model import (
    And,
    Assignment,
    AttrRef,
    ComboAtom,
    ComboRule,
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
    Rule,
    Target,
    VarDecl,
    VarRef,
)
from grammar.validate import formula_pos

_AGM_AN = re.compile(r"[A-Za-z0-9_.]+")


class AgmHead:
    """How AGM's parser reads the words before ``:`` of a rule (``parseAGGL.py``: the rule
    alternatives are tried in order normal, combo, hierarchical, include; ``dormant`` is a
    ``CaselessLiteral`` and ``hierarchical`` a ``Literal``, both matching a prefix of a word)."""

    def __init__(self, name: str, dormant: bool, hierarchical: bool, glued: str | None) -> None:
        self.name = name
        self.dormant = dormant
        self.hierarchical = hierarchical
        self.glued = glued  # the keyword read off the front of a word ("DormantFoo"), for a warning


def _keyword_prefix(text: str, keyword: str, caseless: bool) -> tuple[str, bool, bool]:
    """(rest, matched, glued): ``keyword`` read off the front of ``text`` as pyparsing does."""
    head = text[:len(keyword)]
    if (head.lower() if caseless else head) != keyword:
        return text, False, False
    rest = text[len(keyword):]
    return rest.lstrip(), True, bool(rest) and not rest[0].isspace()


def _single_name(text: str) -> str | None:
    match = _AGM_AN.match(text)
    return match.group(0) if match and not text[match.end():].strip() else None


def read_agm_head(words: list[str], combo: bool = False) -> AgmHead | None:
    """Rule name and flags from the words before ``:``, or ``None`` if AGM cannot read them."""
    text = " ".join(words)
    if combo:  # only the plain 'name : active(N) { atoms where: ... }' form is a combo rule
        return AgmHead(words[0], False, False, None) if len(words) == 1 else None
    rest, dormant, glued = _keyword_prefix(text, "dormant", caseless=True)
    name = _single_name(rest)
    if name is not None:  # AGM's normal rule: [dormant] NAME
        return AgmHead(name, dormant, False, "dormant" if glued else None)
    rest, dormant1, glued1 = _keyword_prefix(text, "dormant", caseless=True)
    rest, hierarchical, glued2 = _keyword_prefix(rest, "hierarchical", caseless=False)
    if not hierarchical:
        return None
    rest, dormant2, glued3 = _keyword_prefix(rest, "dormant", caseless=True)
    name = _single_name(rest)
    if name is None:
        return None
    glued_word = "dormant" if (glued1 or glued3) else "hierarchical" if glued2 else None
    return AgmHead(name, dormant1 or dormant2, True, glued_word)


class _Section:
    """A tagged piece of a rule body, collected by ``n_rule``/``agm_rule``."""

    def __init__(self, kind: str, value: Any, pos: SourcePos | None) -> None:
        self.kind = kind
        self.value = value
        self.pos = pos


class _Stray:
    """A ``)`` left after a formula block's formula (read as AGM reads it: ignored, with a warning)."""

    def __init__(self, pos: SourcePos | None) -> None:
        self.pos = pos


class _Include:
    def __init__(self, path: str, pos: SourcePos) -> None:
        self.path = path
        self.pos = pos


class _Types:
    def __init__(self, entries: list[tuple[list[str], list[str], SourcePos]]) -> None:
        self.entries = entries


def _unquote(token: str) -> str:
    body = token[1:-1]
    return re.sub(r"\\(.)", lambda m: {"n": "\n", "t": "\t"}.get(m.group(1), m.group(1)), body)


def _number(text: str) -> int | float:
    try:
        return int(text)
    except ValueError:
        return float(text)


def _own_attrs(expr: Expr) -> Expr:
    """Inside ``[...]`` a bare name is an attribute of the node/link the block is written on."""
    match expr:
        case VarRef():
            return AttrRef(None, expr.var, expr.pos)
        case Compare():
            return Compare(expr.op, _own_attrs(expr.left), _own_attrs(expr.right))
        case Not():
            return Not(_own_attrs(expr.expr))
        case And():
            return And(tuple(_own_attrs(e) for e in expr.items))
        case Or():
            return Or(tuple(_own_attrs(e) for e in expr.items))
        case ListLit():
            return ListLit(tuple(_own_attrs(e) for e in expr.items))
        case Literal() | AttrRef() | Exists():
            return expr  # its own blocks were converted where written
        case _:
            assert_never(expr)


@v_args(meta=True)
class ModelBuilder(Transformer):
    """Builds model objects; ``file`` is put into every SourcePos."""

    def __init__(self, file: str) -> None:
        super().__init__()
        self.file = file
        self.warnings: list[GrammarWarning] = []

    # ------------------------------------------------------------------ helpers
    def _pos(self, meta: Any) -> SourcePos | None:
        if getattr(meta, "empty", True):
            return None
        return SourcePos(self.file, meta.line, meta.column)

    def _tpos(self, token: Token) -> SourcePos:
        return SourcePos(self.file, token.line or 0, token.column or 0)

    def _error(self, token_or_pos: Token | SourcePos | None, message: str) -> GrammarError:
        pos = self._tpos(token_or_pos) if isinstance(token_or_pos, Token) else token_or_pos
        return GrammarError.at(pos or SourcePos(self.file, 0, 0), message)

    # ------------------------------------------------------------------ formulas
    def precondition(self, meta: Any, items: list[Any]) -> _Section:
        return _Section("precondition", self._single(self._strays(items, "precondition", meta), "precondition", meta),
                        self._pos(meta))

    def effect(self, meta: Any, items: list[Any]) -> _Section:
        return _Section("effect", self._single(self._strays(items, "effect", meta), "effect", meta), self._pos(meta))

    def stray_close(self, meta: Any, c: list[Any]) -> _Stray:
        return _Stray(self._pos(meta))

    def _strays(self, items: list[Any], what: str, meta: Any) -> list[Formula]:
        """The block's formulas; a ``)`` after them is read as AGM reads it (ignored, with a
        warning naming its line), a ``)`` with no formula before it is refused (AGM fails too)."""
        strays = [x for x in items if isinstance(x, _Stray)]
        formulas = [x for x in items if not isinstance(x, _Stray)]
        if strays and not formulas:
            raise self._error(strays[0].pos or self._pos(meta), f"unexpected ')' in an empty {what}")
        for stray in strays:
            self.warnings.append(GrammarWarning(
                stray.pos or self._pos(meta) or SourcePos(self.file, 0, 0),
                f"stray ')' after the {what}'s formula, ignored as AGM ignores it (AGM reads one formula "
                "and skips the rest); remove it ('grammar check --strict' refuses it)"))
        return formulas

    def _single(self, items: list[Formula], what: str, meta: Any) -> Formula | None:
        if len(items) > 1:
            pos = formula_pos(items[1]) or self._pos(meta)
            raise self._error(pos, f"{what} holds {len(items)} formulas; AGM would silently read only "
                                   f"the first: wrap them in (and ...)")
        return items[0] if items else None

    def f_not(self, meta: Any, c: list[Any]) -> FNot:
        return FNot(c[0])

    def f_and(self, meta: Any, c: list[Any]) -> FAnd:
        return FAnd(tuple(c))

    def f_or(self, meta: Any, c: list[Any]) -> FOr:
        return FOr(tuple(c))

    def f_exists(self, meta: Any, c: list[Any]) -> FExists:
        return FExists(tuple(c[:-1]), c[-1])

    def f_forall(self, meta: Any, c: list[Any]) -> FForall:
        return FForall(tuple(c[:-1]), c[-1])

    def f_when(self, meta: Any, c: list[Any]) -> FWhen:
        return FWhen(c[0], c[1])

    def f_create(self, meta: Any, c: list[Token]) -> FCreate:
        return FCreate(str(c[0]), str(c[1]), self._tpos(c[0]))

    def f_delete(self, meta: Any, c: list[Token]) -> FDelete:
        return FDelete(str(c[0]), self._tpos(c[0]))

    def f_retype(self, meta: Any, c: list[Token]) -> FRetype:
        return FRetype(str(c[0]), str(c[1]), self._tpos(c[0]))

    def f_same(self, meta: Any, c: list[Token]) -> FSame:
        names = [t for t in c if t.type != "EQ"]
        return FSame(str(names[0]), str(names[1]), self._tpos(names[0]))

    def f_link(self, meta: Any, c: list[Token]) -> FLink:
        return FLink(str(c[0]), str(c[1]), str(c[2]), self._tpos(c[0]))

    def f_call(self, meta: Any, c: list[Token]) -> Formula:
        raise self._error(c[0], f"function call <{c[0]} ...> is not supported (AGM parses it but "
                                "never gives it a meaning)")

    def vardecl(self, meta: Any, c: list[Token]) -> VarDecl:
        return VarDecl(str(c[0]), str(c[1]), self._tpos(c[0]))

    # ------------------------------------------------------------------ AGM files
    def agm_prop(self, meta: Any, c: list[Token]) -> tuple[str, str]:
        return (str(c[0]), str(c[1]))

    def type_names(self, meta: Any, c: list[Token]) -> list[str]:
        return [str(t) for t in c]

    def type_list(self, meta: Any, c: list[Token]) -> list[str]:
        return [str(t) for t in c]

    def agm_typedef(self, meta: Any, c: list[Any]) -> tuple[list[str], list[str], SourcePos]:
        return _typedef(c, self._pos(meta) or SourcePos(self.file, 0, 0))

    def agm_types(self, meta: Any, c: list[Any]) -> _Types:
        return _Types(list(c))

    def agm_include(self, meta: Any, c: list[Token]) -> _Include:
        if str(c[0]) != "include":
            raise self._error(c[0], f"unexpected '(' after {shorten(str(c[0]))!r}; a rule is "
                                    "'NAME : active(COST) {...}', an include 'include(PATH)'")
        return _Include(str(c[1]).strip(), self._tpos(c[1]))

    def _cost(self, token: Token) -> float:
        digits = str(token).lstrip("+-")
        if len(digits) > 15:
            raise self._error(token, f"cost {shorten(str(token), 20)!r} has {len(digits)} digits; "
                                     "costs are small integers")
        return float(int(str(token)))

    def agm_head(self, meta: Any, c: list[Token]) -> list[Token]:
        return list(c)

    def _head(self, words: list[Token], combo: bool) -> AgmHead:
        head = read_agm_head([str(w) for w in words], combo=combo)
        if head is None:
            text = shorten(" ".join(str(w) for w in words))
            raise self._error(words[0], f"cannot read rule head {text!r}: AGM reads "
                                        "'[dormant] NAME' or '[dormant] hierarchical [dormant] NAME' before ':'")
        if head.glued is not None:
            first = shorten(" ".join(str(w) for w in words))
            kind = ("dormant hierarchical" if head.dormant else "hierarchical") if head.hierarchical else "dormant"
            self.warnings.append(GrammarWarning(
                self._tpos(words[0]),
                f"{first!r} is read as the {kind} rule {shorten(head.name)!r}, as AGM reads it (its "
                f"'{head.glued}' keyword matches the start of a word); write it as a separate word "
                "to make that plain, or rename the rule"))
        return head

    def agm_success(self, meta: Any, c: list[Token]) -> _Section:
        try:
            value = float(str(c[1]))
        except ValueError:
            raise self._error(c[1], f"success({c[1]}) must be a number (a probability)") from None
        return _Section("success", value, self._tpos(c[1]))

    def agm_activates(self, meta: Any, c: list[Token]) -> _Section:
        return _Section("activates", tuple(str(t) for t in c[1:]), self._tpos(c[0]))

    def agm_parameters(self, meta: Any, c: list[VarDecl]) -> _Section:
        return _Section("parameters", tuple(c), self._pos(meta))

    def agm_node(self, meta: Any, c: list[Any]) -> PatternNode:
        name, type_ = str(c[0]), str(c[1])
        return PatternNode(name, type_, pos=self._tpos(c[0]))

    def agm_link(self, meta: Any, c: list[Any]) -> PatternLink:
        src, dst, _bang, label, star = c
        return PatternLink(str(src), str(dst), str(label), negated=star is not None, pos=self._tpos(src))

    def agm_graph(self, meta: Any, c: list[Any]) -> Pattern:
        return Pattern(tuple(x for x in c if isinstance(x, PatternNode)),
                       tuple(x for x in c if isinstance(x, PatternLink)))

    def agm_rule(self, meta: Any, c: list[Any]) -> Rule:
        words, mode, cost = c[0], c[1], c[2]
        head = self._head(words, combo=False)
        if str(mode) not in ("active", "passive"):
            raise self._error(mode, f"expected 'active' or 'passive' after ':' in rule {shorten(head.name)!r}, "
                                    f"got {shorten(str(mode))!r}")
        sections = [x for x in c[3:] if isinstance(x, _Section)]
        graphs = [x for x in c[3:] if isinstance(x, Pattern)]
        by_kind = {s.kind: s.value for s in sections}
        self._warn_rhs_absent_links(head.name, graphs[0], graphs[1])
        return Rule(
            name=head.name, lhs=graphs[0], rhs=graphs[1], cost=self._cost(cost),
            active=str(mode) == "active",
            precondition=by_kind.get("precondition"), effect=by_kind.get("effect"),
            parameters=by_kind.get("parameters", ()),
            hierarchical=head.hierarchical, dormant=head.dormant,
            activates=by_kind.get("activates", ()), success=by_kind.get("success"),
            pos=self._tpos(words[0]),
        )

    def _warn_rhs_absent_links(self, rule: str, lhs: Pattern, rhs: Pattern) -> None:
        """A right-hand-side ``a->b(l)*`` that the left side does not also mark ``*``: AGM's
        ``getLinkChanges`` then adds it as an ordinary link (its ``*`` dropped); chronav reads
        ``*`` as "absent" (docs/grammar.md, "Where chronav deliberately reads AGM files
        differently"), so say where the two planners part."""
        absent_left = {link.key for link in lhs.links if link.negated}
        for link in rhs.links:
            if link.negated and link.key not in absent_left:
                self.warnings.append(GrammarWarning(
                    link.pos or SourcePos(self.file, 0, 0),
                    f"rule {shorten(rule)!r}: right-hand-side link {shorten(link.src)}->{shorten(link.dst)}"
                    f"({shorten(link.label)})* is read as 'this link is absent'; AGM's planner would add it as "
                    "an ordinary link (see docs/grammar.md)"))

    def combo_atom(self, meta: Any, c: list[Any]) -> ComboAtom:
        return ComboAtom(str(c[0]), str(c[1]), optional=c[2] is not None)

    def combo_equiv(self, meta: Any, c: list[Token]) -> tuple[tuple[str, str], ...]:
        names = [str(t) for t in c]
        return tuple((names[i], names[i + 1]) for i in range(0, len(names), 2))

    def agm_combo(self, meta: Any, c: list[Any]) -> ComboRule:
        words, mode, cost = c[0], c[1], c[2]
        name = words[0]
        self._head(words, combo=True)
        if str(mode) not in ("active", "passive"):
            raise self._error(mode, f"expected 'active' or 'passive', got {str(mode)!r}")
        atoms = tuple(x for x in c[3:] if isinstance(x, ComboAtom))
        equivs = tuple(x for x in c[3:] if isinstance(x, tuple))
        return ComboRule(str(name), self._cost(cost), atoms, equivs, str(mode) == "active",
                         self._tpos(name))

    def agm_file(self, meta: Any, c: list[Any]) -> dict[str, Any]:
        props: dict[str, Any] = dict(x for x in c if isinstance(x, tuple))
        types = next((x for x in c if isinstance(x, _Types)), None)
        items = [x for x in c if isinstance(x, (Rule, ComboRule, _Include))]
        return {"dialect": "agm", "properties": props, "name": props.get("name"),
                "types": types.entries if types else [], "items": items}

    def agm_target(self, meta: Any, c: list[Any]) -> Target:
        pattern = next((x for x in c if isinstance(x, Pattern)), Pattern())
        # AGM's generateTarget_AGGT: a name starting with a digit is a constant (a world symbol id)
        nodes = tuple(PatternNode(n.name, n.type, constant=n.name if n.name[:1].isdigit() else None,
                                  pos=n.pos) for n in pattern.nodes)
        pre = next((x.value for x in c if isinstance(x, _Section)), None)
        return Target(Pattern(nodes, pattern.links), precondition=pre, file=self.file)

    # ------------------------------------------------------------------ native files
    def n_name(self, meta: Any, c: list[Token]) -> _Section:
        return _Section("name", str(c[0]), self._tpos(c[0]))

    def n_typedef(self, meta: Any, c: list[Any]) -> tuple[list[str], list[str], SourcePos]:
        return _typedef(c, self._pos(meta) or SourcePos(self.file, 0, 0))

    def n_types(self, meta: Any, c: list[Any]) -> _Types:
        return _Types(list(c))

    def n_include(self, meta: Any, c: list[Token]) -> _Include:
        return _Include(_unquote(str(c[0])), self._tpos(c[0]))

    def flag_cost(self, meta: Any, c: list[Token]) -> _Section:
        return _Section("cost", float(str(c[0])), self._tpos(c[0]))

    def flag_passive(self, meta: Any, c: list[Any]) -> _Section:
        return _Section("active", False, self._pos(meta))

    def flag_active(self, meta: Any, c: list[Any]) -> _Section:
        return _Section("active", True, self._pos(meta))

    def flag_dormant(self, meta: Any, c: list[Any]) -> _Section:
        return _Section("dormant", True, self._pos(meta))

    def flag_hierarchical(self, meta: Any, c: list[Any]) -> _Section:
        return _Section("hierarchical", True, self._pos(meta))

    def flag_activates(self, meta: Any, c: list[Token]) -> _Section:
        return _Section("activates", tuple(str(t) for t in c), self._tpos(c[0]))

    def flag_success(self, meta: Any, c: list[Token]) -> _Section:
        return _Section("success", float(str(c[0])), self._tpos(c[0]))

    def sec_lhs(self, meta: Any, c: list[Pattern]) -> _Section:
        return _Section("lhs", c[0], self._pos(meta))

    def sec_rhs(self, meta: Any, c: list[Pattern]) -> _Section:
        return _Section("rhs", c[0], self._pos(meta))

    def sec_where(self, meta: Any, c: list[Expr]) -> _Section:
        return _Section("where", c[0], self._pos(meta))

    def sec_unless(self, meta: Any, c: list[Pattern]) -> _Section:
        return _Section("where", Not(Exists(c[0], self._pos(meta))), self._pos(meta))

    def sec_set(self, meta: Any, c: list[Any]) -> _Section:
        return _Section("set", Assignment(str(c[0]), str(c[1]), c[2], self._tpos(c[0])), self._tpos(c[0]))

    def sec_parameters(self, meta: Any, c: list[VarDecl]) -> _Section:
        return _Section("parameters", tuple(c), self._pos(meta))

    def cond_block(self, meta: Any, c: list[Expr]) -> tuple[Expr, ...]:
        return tuple(_own_attrs(e) for e in c)

    def n_node(self, meta: Any, c: list[Any]) -> PatternNode:
        name_tok, type_tok, conds = c
        constant = _unquote(str(name_tok)) if name_tok.type == "STRING" else None
        name = constant if constant is not None else str(name_tok)
        return PatternNode(name, str(type_tok), constant=constant, conditions=conds or (),
                           pos=self._tpos(name_tok))

    def n_link(self, meta: Any, c: list[Any]) -> PatternLink:
        not_tok, src, op, dst, label, star, conds = c
        negated = not_tok is not None or star is not None
        return PatternLink(str(src), str(dst), str(label), negated=negated,
                           undirected=str(op) == "--", conditions=conds or (),
                           pos=self._tpos(not_tok or src))

    def n_pattern(self, meta: Any, c: list[Any]) -> Pattern:
        return Pattern(tuple(x for x in c if isinstance(x, PatternNode)),
                       tuple(x for x in c if isinstance(x, PatternLink)))

    def n_rule(self, meta: Any, c: list[Any]) -> Rule:
        name = c[0]
        sections: list[_Section] = list(c[1:])
        single: dict[str, _Section] = {}
        for sec in sections:
            if sec.kind in ("where", "set"):
                continue
            if sec.kind in single:
                raise self._error(sec.pos, f"rule {shorten(str(name))!r} has two '{sec.kind}' sections")
            single[sec.kind] = sec
        for required in ("lhs", "rhs"):
            if required not in single:
                raise self._error(name, f"rule {shorten(str(name))!r} has no '{required}' section")

        def value(kind: str, default: Any) -> Any:
            return single[kind].value if kind in single else default

        return Rule(
            name=str(name), lhs=value("lhs", Pattern()), rhs=value("rhs", Pattern()),
            cost=value("cost", 1.0), active=value("active", True),
            where=tuple(s.value for s in sections if s.kind == "where"),
            precondition=value("precondition", None), effect=value("effect", None),
            assignments=tuple(s.value for s in sections if s.kind == "set"),
            parameters=value("parameters", ()), hierarchical=value("hierarchical", False),
            dormant=value("dormant", False), activates=value("activates", ()),
            success=value("success", None), pos=self._tpos(name),
        )

    def native_file(self, meta: Any, c: list[Any]) -> dict[str, Any]:
        name = next((x.value for x in c if isinstance(x, _Section) and x.kind == "name"), None)
        types = [entry for x in c if isinstance(x, _Types) for entry in x.entries]
        items = [x for x in c if isinstance(x, (Rule, _Include))]
        return {"dialect": "native", "properties": {}, "name": name, "types": types, "items": items}

    def native_target(self, meta: Any, c: list[Any]) -> Target:
        return Target(c[0], where=tuple(c[1:]), file=self.file)

    # ------------------------------------------------------------------ expressions
    def e_or(self, meta: Any, c: list[Expr]) -> Expr:
        return c[0] if len(c) == 1 else Or(tuple(c))

    def e_and(self, meta: Any, c: list[Expr]) -> Expr:
        return c[0] if len(c) == 1 else And(tuple(c))

    def e_not(self, meta: Any, c: list[Any]) -> Expr:
        return Not(c[-1])

    def e_exists(self, meta: Any, c: list[Pattern]) -> Expr:
        return Exists(c[0], self._pos(meta))

    def e_truthy(self, meta: Any, c: list[Expr]) -> Expr:
        return c[0]  # a bare value in a boolean place is tested for truthiness

    def e_compare(self, meta: Any, c: list[Any]) -> Expr:
        return Compare(str(c[1]), c[0], c[2])

    def o_attr(self, meta: Any, c: list[Token]) -> Expr:
        return AttrRef(str(c[0]), str(c[1]), self._tpos(c[0]))

    def o_name(self, meta: Any, c: list[Token]) -> Expr:
        return VarRef(str(c[0]), self._tpos(c[0]))

    def o_string(self, meta: Any, c: list[Token]) -> Expr:
        return Literal(_unquote(str(c[0])))

    def o_number(self, meta: Any, c: list[Token]) -> Expr:
        return Literal(_number(str(c[0])))

    def o_true(self, meta: Any, c: list[Any]) -> Expr:
        return Literal(True)

    def o_false(self, meta: Any, c: list[Any]) -> Expr:
        return Literal(False)

    def o_none(self, meta: Any, c: list[Any]) -> Expr:
        return Literal(None)

    def o_list(self, meta: Any, c: list[Any]) -> Expr:
        return ListLit(tuple(x for x in c if x is not None))


def _typedef(c: list[Any], pos: SourcePos) -> tuple[list[str], list[str], SourcePos]:
    """``(a b : p q)`` / ``a, b : p, q``: every name before the colon inherits from every parent."""
    names, parents = c[0], c[1]
    return list(names), list(parents or []), pos


__all__ = ["ModelBuilder"]
