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
from functools import lru_cache
from pathlib import Path
from typing import Any

from lark import Lark
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken, VisitError

from grammar.errors import GrammarError, SourcePos
from grammar.model import ComboRule, Grammar, Rule, Target, TypeTable
from grammar.transform import ModelBuilder
from grammar.validate import check_grammar, check_rule, check_target

GRAMMAR_DIR = Path(__file__).resolve().parent
LARK_FILE = GRAMMAR_DIR / "aggl.lark"

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
    match = _WORD.match(value)
    return match.group(0) if match else value[:1]


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
        char = text[exc.pos_in_stream] if exc.pos_in_stream < len(text) else ""
        return GrammarError(f"unexpected character {char!r}{_expected(exc.allowed or ())}", file,
                            exc.line, exc.column)
    return GrammarError(str(exc), file, getattr(exc, "line", 0), getattr(exc, "column", 0))


def _parse(text: str, start: str, file: str) -> Any:
    try:
        tree = _lark().parse(text, start=start)
    except UnexpectedInput as exc:
        raise _lark_error(exc, text, file) from None
    try:
        return ModelBuilder(file).transform(tree)
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


def _resolve_include(path: str, including: Path | None, pos: SourcePos) -> Path:
    """Relative to the including file, then the working directory, then ``$AGGLPATH`` (``;`` or ``:``)."""
    candidates: list[Path] = []
    raw = Path(path).expanduser()
    if raw.is_absolute():
        candidates.append(raw)
    else:
        if including is not None:
            candidates.append(including.parent / raw)
        candidates.append(Path.cwd() / raw)
        for entry in re.split(r"[;:]", os.environ.get("AGGLPATH", "")):
            if entry:
                candidates.append(Path(entry) / raw)
    for candidate in candidates:
        if candidate.is_file():
            return candidate.resolve()
    looked = ", ".join(str(c) for c in candidates)
    raise GrammarError.at(pos, f"included file {path!r} not found (looked at: {looked})")


def parse_grammar(text: str, file: str = "<string>", *, dialect: str | None = None,
                  path: Path | None = None, _stack: tuple[Path, ...] = ()) -> Grammar:
    """Parse grammar text; ``path`` (the file it came from) anchors relative includes."""
    dialect = dialect or detect_dialect(text)
    if dialect not in ("agm", "native"):
        raise GrammarError(f"unknown dialect {dialect!r} (use 'agm' or 'native')", file, 1, 1)
    raw = _parse(text, "agm_file" if dialect == "agm" else "native_file", file)
    types = _build_types(raw["types"])
    rules: list[Rule] = []
    combos: list[ComboRule] = []
    includes: list[str] = []
    for item in raw["items"]:
        if isinstance(item, Rule):
            check_rule(item)
            rules.append(item)
        elif isinstance(item, ComboRule):
            combos.append(item)
        else:  # an include: its rules (and types) are spliced in at this place
            target = _resolve_include(item.path, path, item.pos)
            if target in _stack or target == path:
                raise GrammarError.at(item.pos, f"include cycle: {item.path!r} includes itself")
            stack = _stack + ((path,) if path is not None else ())
            inner = load_grammar(target, _stack=stack)
            rules.extend(inner.rules)
            combos.extend(inner.combos)
            includes.append(str(target))
            includes.extend(inner.includes)
            for name, supers in inner.types.parents.items():
                types.setdefault(name, supers)
    name = raw["name"] or (path.stem if path else "grammar")
    grammar = Grammar(name=str(name), rules=tuple(rules), types=TypeTable(types), file=file,
                      dialect=dialect, properties=raw["properties"], combos=tuple(combos),
                      includes=tuple(includes))
    check_grammar(grammar)
    return grammar


def load_grammar(path: str | os.PathLike[str], *, dialect: str | None = None,
                 _stack: tuple[Path, ...] = ()) -> Grammar:
    """Read and parse a grammar file (either dialect); includes resolve relative to it."""
    file_path = Path(path)
    try:
        text = file_path.read_text(encoding="utf-8")
    except OSError as exc:
        raise GrammarError(f"cannot read grammar file: {exc.strerror or exc}", str(path), 0, 0) from None
    except UnicodeDecodeError as exc:
        raise GrammarError(f"not UTF-8 text ({exc.reason})", str(path), 1, 1) from None
    return parse_grammar(text, str(path), dialect=dialect, path=file_path.resolve(), _stack=_stack)


def parse_target(text: str, file: str = "<string>") -> Target:
    """Parse an AGM ``.aggt`` target, or a native ``target { ... } where ...`` one."""
    first = _FIRST_WORD.match(re.sub(r"#[^\n]*", "", text).lstrip())
    start = "native_target" if first and first.group(0) == "target" else "agm_target"
    target: Target = _parse(text, start, file)
    check_target(target)
    return target


def load_target(path: str | os.PathLike[str]) -> Target:
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise GrammarError(f"cannot read target file: {exc.strerror or exc}", str(path), 0, 0) from None
    except UnicodeDecodeError as exc:
        raise GrammarError(f"not UTF-8 text ({exc.reason})", str(path), 1, 1) from None
    return parse_target(text, str(path))


def default_grammar_path() -> Path:
    """The social navigation grammar shipped with chronav."""
    return GRAMMAR_DIR / "social_navigation.aggl"
