"""Load grammar (.aggl) and target (.aggt) files of either dialect into the typed model.

Why one entry point for both dialects: users keep their old RoboComp AGM grammars next to new
chronav ones, and an ``include`` may cross dialects. The dialect is told by the first word:
an AGM file starts with its ``key=value`` header, a native file with ``grammar``, ``types``,
``include`` or ``rule``; a native target starts with ``target``.

Every error is a :class:`GrammarError` carrying file, line, column and what was expected.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterable
from dataclasses import replace
from functools import lru_cache
from pathlib import Path
from typing import Any

from lark import Lark, Tree
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken, VisitError

from scenes.reading import read_bounded, regular_file_problem
from grammar.errors import MAX_PATH_CHARS, GrammarError, GrammarWarning, SourcePos, shorten
from grammar.model import ComboRule, Grammar, Rule, Target, TypeTable
from grammar.transform import ModelBuilder
from grammar.validate import check_grammar, check_rule, check_target

GRAMMAR_DIR = Path(__file__).resolve().parent
LARK_FILE = GRAMMAR_DIR / "aggl.lark"

MAX_GRAMMAR_BYTES = 16 * 1024 * 1024
"""Largest grammar or target file read (AGM's biggest real grammars are some 100 KB)."""
MAX_INCLUDES = 200
"""Includes read in all while loading one grammar (docs/limits.md): 24 files each including the
next twice asked for 2^24 reads; real grammars include a handful of files once each."""
MAX_NESTING = 100
"""Deepest parse tree accepted (docs/grammar.md, "Limits"): one level per formula connective
(``not``, ``and``, ``exists``...), about three per parenthesis of a ``where``. Deeper input is
refused with its position instead of exhausting Python's recursion limit in the later passes."""

MAX_COST_DIGITS = 15
"""An AGM cost is an integer; more digits than this is a typo, not a cost (and Python refuses to
convert integers of more than 4300 digits)."""

MAX_LISTED_PLACES = 8
"""Places an include-not-found error lists (each path whole): the including file's directory,
the working directory and the first $AGGLPATH entries."""

_AGM_HEADER = re.compile(r"^\s*[A-Za-z0-9_.]+\s*=(?!=)")
_FIRST_WORD = re.compile(r"[A-Za-z_]+")
_WORD = re.compile(r"[A-Za-z0-9_.]+|[^\sA-Za-z0-9_.]+")

# What to call lark's terminals in "expected ..." messages.
_TERMINAL_NAMES = {
    "AN": "a name", "ID": "a name", "INT": "an integer", "NUMBER": "a number",
    "STRING": 'a quoted string', "INCLUDE_PATH": "a file path", "LINK_OP": "'->' or '--'",
    "COMP_OP": "a comparison (== != < <= > >= in)", "SUCCESS": "'success'",
    "ACTIVATES": "'activates'", "$END": "end of file",
}


@lru_cache(maxsize=1)
def _lark() -> Lark:
    return Lark(LARK_FILE.read_text(encoding="utf-8"), parser="lalr",
                start=["agm_file", "agm_target", "native_file", "native_target"],
                propagate_positions=True, maybe_placeholders=True,
                cache=True)  # lark keeps the analysed LALR tables in a temp file: ~3x faster start


def _describe(name: str) -> str:
    if name in _TERMINAL_NAMES:
        return _TERMINAL_NAMES[name]
    try:
        pattern = _lark().get_terminal(name).pattern
    except KeyError:
        return name
    if pattern.type == "str":
        return repr(pattern.value)
    return name.lower()


def _expected(names: Any) -> str:
    described = sorted({_describe(n) for n in names})
    if not described:
        return ""
    if len(described) == 1:
        return f"; expected {described[0]}"
    return "; expected one of " + ", ".join(described)


def _end_position(text: str) -> tuple[int, int]:
    lines = text.split("\n")
    return len(lines), len(lines[-1]) + 1


def _first_word(value: str) -> str:
    match = _WORD.match(value[:200])
    return shorten(match.group(0) if match else value[:1], 40)


def _accepted(exc: UnexpectedToken) -> Any:
    """Terminals really acceptable here (LALR's table lists a superset after state merging)."""
    try:
        return exc.interactive_parser.accepts() - {"$END"} | ({"$END"} & set(exc.expected))
    except Exception:  # noqa: BLE001 - best effort: fall back to the table's list
        return exc.expected


def _lark_error(exc: UnexpectedInput, text: str, file: str) -> GrammarError:
    if isinstance(exc, UnexpectedToken) and exc.token.type != "$END":
        token = exc.token
        return GrammarError(f"unexpected {_first_word(str(token))!r}{_expected(_accepted(exc))}", file,
                            token.line or 0, token.column or 0)
    if isinstance(exc, UnexpectedToken):
        line, column = _end_position(text.rstrip())
        return GrammarError(f"unexpected end of file{_expected(_accepted(exc))}", file, line, column)
    if isinstance(exc, UnexpectedEOF):
        line, column = _end_position(text.rstrip())
        return GrammarError(f"unexpected end of file{_expected(exc.expected)}", file, line, column)
    if isinstance(exc, UnexpectedCharacters):
        pos = exc.pos_in_stream or 0   # lark types it Optional; a character error always has one
        char = text[pos] if pos < len(text) else ""
        return GrammarError(f"unexpected character {char!r}{_expected(exc.allowed or ())}", file,
                            exc.line, exc.column)
    return GrammarError(str(exc), file, getattr(exc, "line", 0), getattr(exc, "column", 0))


def _check_depth(tree: Tree, file: str) -> None:
    """Refuse trees deeper than ``MAX_NESTING`` (walked without recursion)."""
    stack: list[tuple[Tree, int]] = [(tree, 1)]
    while stack:
        node, depth = stack.pop()
        if depth > MAX_NESTING:
            meta = node.meta
            line, column = (meta.line, meta.column) if not getattr(meta, "empty", True) else (1, 1)
            raise GrammarError(f"nested too deeply: more than {MAX_NESTING} levels of formulas, "
                               "expressions or patterns (see 'Limits' in docs/grammar.md)", file, line, column)
        stack.extend((child, depth + 1) for child in node.children if isinstance(child, Tree))


def _parse(text: str, start: str, file: str) -> tuple[Any, list[GrammarWarning]]:
    try:
        tree = _lark().parse(text, start=start)
    except UnexpectedInput as exc:
        raise _lark_error(exc, text, file) from None
    _check_depth(tree, file)
    builder = ModelBuilder(file)
    try:
        return builder.transform(tree), builder.warnings
    except VisitError as exc:  # an error raised inside a transformer callback
        if isinstance(exc.orig_exc, GrammarError):
            raise exc.orig_exc from None
        raise


def detect_dialect(text: str) -> str:
    """``agm`` when the first non-comment line is a ``key=value`` header line, else ``native``."""
    for line in text.splitlines():
        stripped = line.strip()
        if not stripped or stripped.startswith("#"):
            continue
        return "agm" if _AGM_HEADER.match(stripped) else "native"
    return "native"


def _build_types(entries: list[tuple[list[str], list[str], SourcePos]]) -> dict[str, tuple[str, ...]]:
    parents: dict[str, tuple[str, ...]] = {}
    for names, supers, pos in entries:
        for parent in supers:
            if parent not in parents:
                raise GrammarError.at(pos, f"type {names[0]!r} inherits from {parent!r}, which is not "
                                           "declared earlier in the types section")
        for name in names:
            if name in supers:
                raise GrammarError.at(pos, f"type {name!r} cannot inherit from itself")
            merged = parents.get(name, ()) + tuple(p for p in supers if p not in parents.get(name, ()))
            parents[name] = merged
    return parents


def _agglpath() -> list[Path]:
    return [Path(entry) for entry in re.split(r"[;:]", os.environ.get("AGGLPATH", "")) if entry]


def _resolve_include(path: str, including: Path | None, pos: SourcePos) -> Path:
    """Where an ``include`` file is, looked up as AGM does (``parseAGGL.py``: the path under ``/``,
    ``.`` and each ``$AGGLPATH`` directory, so that the absolute paths of the authors' machines
    found in real grammars resolve under a local copy), after the including file's directory."""
    candidates: list[Path] = []
    raw = Path(path).expanduser()
    relative = Path(*raw.parts[1:]) if raw.is_absolute() else raw  # '/a/b.aggl' -> 'a/b.aggl'
    if raw.is_absolute():
        candidates.append(raw)
    elif including is not None:
        candidates.append(including.parent / raw)
    candidates.append(Path.cwd() / relative)
    candidates.extend(entry / relative for entry in _agglpath())
    for candidate in candidates:
        if candidate.is_file():
            return candidate.resolve()
        problem = regular_file_problem(candidate) if candidate.exists() else None
        if problem is not None:   # a FIFO or a directory is not "not found": say what it is
            raise GrammarError.at(pos, f"included file {shorten(path, MAX_PATH_CHARS)!r} at "
                                       f"{shorten(str(candidate), MAX_PATH_CHARS)} {problem}")
    looked = "; ".join(shorten(str(c), MAX_PATH_CHARS) for c in candidates[:MAX_LISTED_PLACES])
    more = f" and {len(candidates) - MAX_LISTED_PLACES} more" if len(candidates) > MAX_LISTED_PLACES else ""
    raise GrammarError.at(pos, f"included file {shorten(path, MAX_PATH_CHARS)!r} not found (looked at: "
                               f"{looked}{more}); set AGGLPATH to the directories that hold it",
                          limit=(MAX_LISTED_PLACES + 1) * (MAX_PATH_CHARS + 10) + 200)


def _refuse_warnings(warnings: Iterable[GrammarWarning]) -> None:
    """``strict``: the first warning (something AGM reads but that is probably a mistake) is an error."""
    for warning in warnings:
        raise GrammarError.at(warning.pos, f"{warning.message} [strict check: warnings are errors]")


def _resolve_redefinitions(rules: list[Rule], warnings: list[GrammarWarning]) -> list[Rule]:
    """A rule defined in one file and again in another (an included one): the later definition
    wins, as in AGM (its rules are kept in one list, included rules where the ``include`` is,
    and the generated planner defines one method per name, so the last one stands); a warning
    names both places. The same rule met twice through two includes of one file is kept once.
    Two definitions in one file stay an error (check_grammar): that is a mistake, not a reuse."""
    winner: dict[str, int] = {}
    for i, rule in enumerate(rules):
        winner[rule.name] = i
    kept: list[Rule] = []
    for i, rule in enumerate(rules):
        later = rules[winner[rule.name]]
        if i == winner[rule.name] or rule.pos is None or later.pos is None:
            kept.append(rule)
        elif rule.pos == later.pos:
            continue  # one file included twice: the same definition
        elif rule.pos.file == later.pos.file:
            kept.append(rule)  # refused by check_grammar ("defined twice")
        else:
            warnings.append(GrammarWarning(later.pos, f"rule {shorten(rule.name)!r} is defined again here; "
                                                      f"AGM uses the later definition, so this one replaces "
                                                      f"the one at {rule.pos}"))
    return kept


def parse_grammar(text: str, file: str = "<string>", *, dialect: str | None = None,
                  path: Path | None = None, includes: bool = True, strict: bool = False,
                  _stack: tuple[Path, ...] = (), _included: list[int] | None = None) -> Grammar:
    """Parse grammar text; ``path`` (the file it came from) anchors relative includes.
    ``includes=False`` checks the text alone, as AGM's ``includeIncludes=False``. ``strict``
    refuses what is only warned about otherwise (what AGM accepts but is probably a mistake:
    a stray ``)`` after a formula, a rule redefined across an include...)."""
    text = text.removeprefix("\ufeff")
    if not _stack and all(not line.strip() or line.lstrip().startswith("#") for line in text.splitlines()):
        raise GrammarError("the file is empty (nothing but blank lines and comments): a grammar needs at "
                           "least one rule", file, 1, 1)
    dialect = dialect or detect_dialect(text)
    if dialect not in ("agm", "native"):
        raise GrammarError(f"unknown dialect {shorten(dialect)!r} (use 'agm' or 'native')", file, 1, 1)
    raw, warnings = _parse(text, "agm_file" if dialect == "agm" else "native_file", file)
    types = _build_types(raw["types"])
    rules: list[Rule] = []
    combos: list[ComboRule] = []
    included: list[str] = []
    skipped: list[str] = []
    for item in raw["items"]:
        if isinstance(item, Rule):
            check_rule(item)
            rules.append(item)
        elif isinstance(item, ComboRule):
            combos.append(item)
        elif not includes:
            skipped.append(item.path)
        else:  # an include: its rules (and types) are spliced in at this place
            target = _resolve_include(item.path, path, item.pos)
            if target in _stack or target == path:
                raise GrammarError.at(item.pos, f"include cycle: {shorten(item.path)!r} includes itself")
            stack = _stack + ((path,) if path is not None else ())
            _included = [0] if _included is None else _included   # shared by the whole include tree
            _included[0] += 1
            if _included[0] > MAX_INCLUDES:   # files including the next twice: 2^24 loads
                raise GrammarError.at(item.pos, f"more than {MAX_INCLUDES} includes in all (an include inside an "
                                                "included file counts each time it is read); include each file once")
            inner = load_grammar(target, _stack=stack, _included=_included)
            rules.extend(inner.rules)
            combos.extend(inner.combos)
            warnings.extend(inner.warnings)
            included.append(str(target))
            included.extend(inner.includes)
            for name, supers in inner.types.parents.items():
                types.setdefault(name, supers)
    rules = _resolve_redefinitions(rules, warnings)
    name = raw["name"] or (path.stem if path else "grammar")
    grammar = Grammar(name=str(name), rules=tuple(rules), types=TypeTable(types), file=file,
                      dialect=dialect, properties=raw["properties"], combos=tuple(combos),
                      includes=tuple(included), skipped_includes=tuple(skipped),
                      declared_types=bool(types), warnings=tuple(warnings))
    check_grammar(grammar, top_level=not _stack)
    if strict:
        _refuse_warnings(grammar.warnings)
    return grammar


def _read(path: str | os.PathLike[str], what: str) -> str:
    """A grammar or target file's text (UTF-8, an initial byte-order mark allowed)."""
    try:   # a regular file of at most MAX_GRAMMAR_BYTES: never /dev/zero, a FIFO or a directory
        data = read_bounded(path, max_bytes=MAX_GRAMMAR_BYTES, what=f"{what} file")
    except FileNotFoundError:
        raise GrammarError(f"{what} file not found", str(path)) from None
    except ValueError as exc:
        raise GrammarError(str(exc), str(path)) from None
    except OSError as exc:
        raise GrammarError(f"cannot read {what} file: {exc.strerror or exc}", str(path)) from None
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        column = exc.start - (data.rfind(b"\n", 0, exc.start) + 1) + 1
        raise GrammarError(f"not UTF-8 text ({exc.reason})", str(path), line, column) from None


def load_grammar(path: str | os.PathLike[str], *, dialect: str | None = None, includes: bool = True,
                 strict: bool = False, _stack: tuple[Path, ...] = (),
                 _included: list[int] | None = None) -> Grammar:
    """Read and parse a grammar file (either dialect); includes resolve relative to it."""
    text = _read(path, "grammar")
    return parse_grammar(text, str(path), dialect=dialect, path=Path(path).resolve(), includes=includes,
                         strict=strict, _stack=_stack, _included=_included)


def parse_target(text: str, file: str = "<string>", *, strict: bool = False) -> Target:
    """Parse an AGM ``.aggt`` target, or a native ``target { ... } where ...`` one."""
    text = text.removeprefix("\ufeff")
    start = "agm_target"
    for line in text.splitlines():
        stripped = line.strip()
        if stripped and not stripped.startswith("#"):
            first = _FIRST_WORD.match(stripped)
            start = "native_target" if first and first.group(0) == "target" else "agm_target"
            break
    target, warnings = _parse(text, start, file)
    check_target(target)
    if strict:
        _refuse_warnings(warnings)
    return replace(target, warnings=tuple(warnings)) if warnings else target


def load_target(path: str | os.PathLike[str], *, strict: bool = False) -> Target:
    return parse_target(_read(path, "target"), str(path), strict=strict)


def default_grammar_path() -> Path:
    """The social navigation grammar shipped with chronav."""
    return GRAMMAR_DIR / "social_navigation.aggl"
