"""The one YAML reader of chronav: plain data plus where every value came from, within bounds.

Why: a care-home technician editing a scene, an agenda file or the write policy needs errors
that say ``scenes/center_a.yaml:42:7: objects[2].pose: ...``, not a pydantic dump or a Python
traceback.  PyYAML's composer keeps marks on each node; we compose once and build the data
ourselves from the nodes, recording the line/column of every key path, so that validation
errors can be mapped back to the file.  Building the data ourselves is also what keeps reading
bounded (scenes/limits.py): nesting depth is checked while composing (PyYAML recurses), every
value produced counts against an expansion budget (a "billion laughs" file of nested aliases
fails after a few hundred thousand values instead of filling memory), integers and texts have
a length bound, and invalid dates (``2026-13-45``) or duplicate keys are located errors.

Resolution follows YAML 1.1 as PyYAML does, except that sexagesimal numbers are not numbers:
an unquoted ``start: 11:00`` stays the text "11:00" (YAML 1.1 would read 660).  ``text_data``
gives a part of the document with every scalar as the text typed (what the agenda reader
wants: ``name: 123`` is the name "123").

:class:`SourceError` is the one located error of every input file chronav reads (YAML, .ics,
trajectory CSV): file, line, column, key path and a message in the user's words.
"""

from __future__ import annotations

import datetime as dt
import difflib
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar, cast

import yaml
from pydantic import BaseModel, ValidationError

from scenes.errors import SourceError
from scenes.files import read_text_bounded
from scenes.limits import TEXT_CHARS, YAML_BYTES, YAML_DEPTH, YAML_INT_DIGITS, YAML_NODES

KeyPath = tuple[str | int, ...]
M = TypeVar("M", bound=BaseModel)

_NULL = "tag:yaml.org,2002:null"
_INT = "tag:yaml.org,2002:int"
_FLOAT = "tag:yaml.org,2002:float"
_STR = "tag:yaml.org,2002:str"
_TIMESTAMP = "tag:yaml.org,2002:timestamp"
_MERGE = "tag:yaml.org,2002:merge"


def format_key(path: KeyPath) -> str:
    text = ""
    for part in path:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text


# ---------------------------------------------------------------------------------------------
# Loading.
# ---------------------------------------------------------------------------------------------

class _Loader(yaml.SafeLoader):
    """SafeLoader with a bounded composer and without YAML 1.1's sexagesimal numbers."""

    max_depth = YAML_DEPTH.default

    def __init__(self, stream: str) -> None:
        super().__init__(stream)
        self._depth = 0

    def compose_node(self, parent: Any, index: Any) -> Any:  # PyYAML recurses here, once per level
        self._depth += 1
        try:
            if self._depth > self.max_depth:
                mark = self.peek_event().start_mark
                raise _TooDeep(mark)
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1


class _TooDeep(Exception):
    def __init__(self, mark: Any) -> None:
        self.mark = mark


# Copy SafeLoader's implicit resolvers without the sexagesimal forms of int and float.
_Loader.yaml_implicit_resolvers = {}
for _first, _resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items():
    _Loader.yaml_implicit_resolvers[_first] = list(_resolvers)
_NUMBER_TAGS = (_INT, _FLOAT)
for _tag, _pattern in ((_INT, r"""^(?:[-+]?0b[0-1_]+
                    |[-+]?0[0-7_]+
                    |[-+]?(?:0|[1-9][0-9_]*)
                    |[-+]?0x[0-9a-fA-F_]+)$"""),
                       (_FLOAT, r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+][0-9]+)?
                    |\.[0-9_]+(?:[eE][-+][0-9]+)?
                    |[-+]?\.(?:inf|Inf|INF)
                    |\.(?:nan|NaN|NAN))$""")):
    for _first in list(_Loader.yaml_implicit_resolvers):
        _Loader.yaml_implicit_resolvers[_first] = [
            (t, r) for t, r in _Loader.yaml_implicit_resolvers[_first] if t != _tag]
    _Loader.add_implicit_resolver(_tag, re.compile(_pattern, re.X), list("-+0123456789."))


_FastLoader: type[yaml.CSafeLoader] | None = None   # stays None where PyYAML was built without libyaml
if getattr(yaml, "CSafeLoader", None) is not None:
    class _LibyamlLoader(yaml.CSafeLoader):
        """libyaml's parser and composer (30x faster) with the same resolvers as ``_Loader``."""

    _LibyamlLoader.yaml_implicit_resolvers = _Loader.yaml_implicit_resolvers
    _FastLoader = _LibyamlLoader


def _compose(text: str, max_depth: int) -> yaml.Node | None:
    """The document's node tree, refusing nesting deeper than ``max_depth`` before composing it
    (composers recurse once per level).  libyaml when PyYAML has it: a first pass over the events
    (a flat loop) measures the depth, then libyaml composes."""
    if _FastLoader is None:
        slow = _Loader(text)
        slow.max_depth = max_depth
        try:
            return slow.get_single_node()
        finally:
            slow.dispose()
    events = _FastLoader(text)
    try:
        depth = 0
        while events.check_event():
            event = events.get_event()
            if isinstance(event, yaml.CollectionStartEvent):
                depth += 1
                if depth > max_depth:
                    raise _TooDeep(event.start_mark)
            elif isinstance(event, yaml.CollectionEndEvent):
                depth -= 1
    finally:
        events.dispose()
    loader = _FastLoader(text)
    try:
        return loader.get_single_node()
    finally:
        loader.dispose()


@dataclass(frozen=True)
class LocatedYaml:
    """Plain Python data plus the (line, column) of each key path, both 1-based."""

    data: Any
    marks: dict[KeyPath, tuple[int, int]]
    file: str
    root: yaml.Node | None = field(default=None, repr=False, compare=False)

    def where(self, path: KeyPath) -> tuple[int, int]:
        """Position of the deepest prefix of ``path`` that exists in the file."""
        for cut in range(len(path), -1, -1):
            mark = self.marks.get(tuple(path[:cut]))
            if mark is not None:
                return mark
        return (1, 1)

    def error(self, path: KeyPath, message: str) -> SourceError:
        line, column = self.where(path)
        return SourceError(self.file, line, column, format_key(path), message)

    def text_data(self, path: KeyPath = ()) -> Any:
        """The value at ``path`` with every scalar as the text typed (None for null), or None if absent."""
        node = self.root
        for part in path:
            if isinstance(node, yaml.MappingNode) and isinstance(part, str):
                node = next((v for k, v in _pairs(node) if k.value == part), None)
            elif isinstance(node, yaml.SequenceNode) and isinstance(part, int) and part < len(node.value):
                node = node.value[part]
            else:
                return None
        if node is None:
            return None
        return _Builder(self.file, None, text=True).build(node, path)


def _pairs(node: yaml.MappingNode) -> list[tuple[yaml.Node, yaml.Node]]:
    """A mapping's (key, value) nodes with ``<<`` merges applied (explicit keys win, as in YAML)."""
    own: list[tuple[yaml.Node, yaml.Node]] = []
    merged: list[tuple[yaml.Node, yaml.Node]] = []
    for key, value in node.value:
        if key.tag == _MERGE:
            sources = value.value if isinstance(value, yaml.SequenceNode) else [value]
            for source in sources:
                if isinstance(source, yaml.MappingNode):
                    merged.extend(_pairs(source))
        else:
            own.append((key, value))
    names = {k.value for k, _ in own if isinstance(k, yaml.ScalarNode)}
    seen: set[str] = set()
    extra = []
    for key, value in merged:
        if isinstance(key, yaml.ScalarNode) and key.value not in names and key.value not in seen:
            seen.add(key.value)
            extra.append((key, value))
    return own + extra


def _position(mark: Any) -> tuple[int, int]:
    return (mark.line + 1, mark.column + 1)


def _describe_date_error(text: str) -> str:
    return (f"{text!r} is not a valid date or time (use YYYY-MM-DD, e.g. 2026-11-25, or an ISO "
            "date-time such as 2026-11-25T11:00; months 01-12, days that exist in that month, hours 00-23)")


class _Builder:
    """Nodes -> plain data, recording marks, within the node budget (aliases counted every time)."""

    def __init__(self, file: str, marks: dict[KeyPath, tuple[int, int]] | None, *, text: bool) -> None:
        self.file = file
        self.marks = marks
        self.text = text
        self.max_nodes = YAML_NODES.value()
        self.budget = self.max_nodes
        self.max_depth = YAML_DEPTH.value()
        self.text_chars = TEXT_CHARS.value()
        self.int_digits = YAML_INT_DIGITS.value()
        self.constructor = yaml.SafeLoader("")  # only its scalar constructors are used

    def fail(self, node: yaml.Node, path: KeyPath, message: str) -> SourceError:
        line, column = _position(node.start_mark)
        return SourceError(self.file, line, column, format_key(path), message)

    def build(self, node: yaml.Node, path: KeyPath) -> Any:
        self.budget -= 1
        if self.budget < 0:
            raise self.fail(node, path, f"the file expands to more than {self.max_nodes:,} values "
                            "(nested aliases such as *name repeat what they point to); write the values "
                            f"out or raise {YAML_NODES.env}")
        if len(path) > self.max_depth:  # aliases can nest deeper than the text does
            raise self.fail(node, path, f"nested more than {self.max_depth} levels deep")
        if self.marks is not None:
            self.marks.setdefault(path, _position(node.start_mark))
        if isinstance(node, yaml.MappingNode):
            return self.mapping(node, path)
        if isinstance(node, yaml.SequenceNode):
            return [self.build(item, (*path, index)) for index, item in enumerate(node.value)]
        return self.scalar(cast(yaml.ScalarNode, node), path)   # the third and last kind of node

    def mapping(self, node: yaml.MappingNode, path: KeyPath) -> dict[Any, Any]:
        data: dict[Any, Any] = {}
        first: dict[Any, yaml.Node] = {}
        for key_node, value_node in _pairs(node):
            if not isinstance(key_node, yaml.ScalarNode):
                raise self.fail(key_node, path, "a key must be a plain name, not a list or a mapping")
            key = key_node.value if self.text else self.scalar(key_node, path)
            if isinstance(key, float | bool) or key is None:
                key = key_node.value  # `1.5:` / `yes:` / `~:` keys are names as typed
            if key in first:
                line, column = _position(first[key].start_mark)
                raise self.fail(key_node, (*path, key), f"duplicate key {str(key)!r} (first on line {line}, "
                                f"column {column}); a key may appear once in a mapping")
            first[key] = key_node
            data[key] = self.build(value_node, (*path, key))
            if self.marks is not None:  # point a key's errors at the key itself, where people look
                self.marks[(*path, key)] = _position(key_node.start_mark)
        return data

    def scalar(self, node: yaml.ScalarNode, path: KeyPath) -> Any:
        value = node.value
        if len(value) > self.text_chars:
            raise self.fail(node, path, f"a value of {len(value):,} characters; chronav reads at most "
                            f"{self.text_chars:,} ({TEXT_CHARS.env})")
        if self.text:
            return None if node.tag == _NULL else value
        if node.tag == _INT and sum(ch.isdigit() for ch in value) > self.int_digits:
            raise self.fail(node, path, f"a number of {sum(ch.isdigit() for ch in value):,} digits; "
                            f"chronav reads at most {self.int_digits} ({YAML_INT_DIGITS.env})")
        try:
            return self.constructor.construct_object(node, deep=True)
        except ValueError:
            if node.tag == _TIMESTAMP:
                raise self.fail(node, path, _describe_date_error(value)) from None
            raise self.fail(node, path, f"{value!r} is not a valid {node.tag.rsplit(':', 1)[-1]}") from None
        except (yaml.constructor.ConstructorError, TypeError, OverflowError):
            raise self.fail(node, path, f"unsupported YAML tag {node.tag!r}; write plain values") from None


def load_located(text: str, file: str) -> LocatedYaml:
    """Parse YAML text within the limits; every problem is a SourceError with its position."""
    text = text.removeprefix("\ufeff")  # a byte-order mark, as some Windows editors write
    max_bytes = YAML_BYTES.value()
    if len(text) > max_bytes:
        raise SourceError(file, None, None, "", f"{len(text):,} characters; a YAML file may have at most "
                          f"{max_bytes:,} ({YAML_BYTES.env})")
    try:
        node = _compose(text, YAML_DEPTH.value())  # the reader already refuses control characters here
    except _TooDeep as exc:
        line, column = _position(exc.mark)
        raise SourceError(file, line, column, "", f"nested more than {YAML_DEPTH.value()} levels deep; "
                          f"a scene needs a handful ({YAML_DEPTH.env})") from None
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line, column = _position(mark) if mark else (1, 1)
        if "maximum nesting depth" in str(exc.problem):  # libyaml's own bound (1,000) met first
            raise SourceError(file, line, column, "", f"nested more than {YAML_DEPTH.value()} levels deep; "
                              f"a scene needs a handful ({YAML_DEPTH.env})") from None
        raise SourceError(file, line, column, "", f"YAML syntax error: {exc.problem}") from None
    except yaml.reader.ReaderError as exc:
        line = text.count("\n", 0, exc.position) + 1
        column = exc.position - (text.rfind("\n", 0, exc.position) + 1) + 1
        raise SourceError(file, line, column, "", f"control character U+{exc.character:04X} is not allowed in YAML") from None
    except yaml.YAMLError as exc:
        raise SourceError(file, 1, 1, "", f"YAML error: {exc}") from None
    except RecursionError:  # belt and braces: the depth bound is far below Python's
        raise SourceError(file, None, None, "", "nested too deeply to read") from None
    marks: dict[KeyPath, tuple[int, int]] = {}
    data = _Builder(file, marks, text=False).build(node, ()) if node is not None else None
    return LocatedYaml(data=data, marks=marks, file=file, root=node)


def read_text_file(path: str | Path, *, max_bytes: int, limit_env: str, what: str = "file") -> str:
    """A UTF-8 text file (a leading byte-order mark dropped), size-checked before it is read; only a
    regular file (scenes/files.py: a FIFO, a directory or /dev/zero is refused as such)."""
    return read_text_bounded(path, max_bytes=max_bytes, limit_env=limit_env, what=what)


def load_located_file(path: str | Path) -> LocatedYaml:
    text = read_text_file(path, max_bytes=YAML_BYTES.value(), limit_env=YAML_BYTES.env, what="YAML file")
    return load_located(text, str(path))


# ---------------------------------------------------------------------------------------------
# Validation errors in the user's words.
# ---------------------------------------------------------------------------------------------

def _show(value: Any) -> str:
    if value is None:
        return "nothing (null)"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, dict):
        return "a mapping"
    if isinstance(value, list | tuple):
        return "a list"
    text = repr(value) if isinstance(value, str) else str(value)
    return text if len(text) <= 60 else text[:57] + "..."


_TYPE_WORDS = {
    "model_type": "a mapping (key: value lines)", "dict_type": "a mapping (key: value lines)",
    "model_attributes_type": "a mapping (key: value lines)", "list_type": "a list", "tuple_type": "a list",
    "string_type": "text", "float_type": "a number", "float_parsing": "a number", "int_type": "a whole number",
    "int_parsing": "a whole number", "int_from_float": "a whole number", "bool_type": "true or false",
    "bool_parsing": "true or false", "date_type": "a date such as 2026-11-25",
    "date_parsing": "a date such as 2026-11-25", "date_from_datetime_parsing": "a date such as 2026-11-25",
}


def user_message(error: Any) -> str:
    """One pydantic error -> a sentence without library jargon (the key path is printed apart)."""
    kind, ctx, value = error["type"], error.get("ctx") or {}, error.get("input")
    if kind == "missing":
        return "required key is missing"
    if kind in _TYPE_WORDS:
        return f"expected {_TYPE_WORDS[kind]}, got {_show(value)}"
    if kind in ("value_error", "assertion_error"):
        return str(error["msg"]).removeprefix("Value error, ").removeprefix("Assertion failed, ")
    if kind == "finite_number":
        return f"must be a finite number, got {_show(value)}"
    bounds = {"greater_than": "greater than", "greater_than_equal": "at least", "less_than": "less than",
              "less_than_equal": "at most"}
    if kind in bounds:
        limit = next(iter(ctx.values()), "?")
        return f"must be {bounds[kind]} {limit}, got {_show(value)}"
    if kind in ("too_short", "too_long"):
        count = ctx.get("min_length", ctx.get("max_length", "?"))
        return f"needs {'at least' if kind == 'too_short' else 'at most'} {count} items, got {ctx.get('actual_length', '?')}"
    if kind in ("string_too_short", "string_too_long"):
        count = ctx.get("min_length", ctx.get("max_length", "?"))
        what = "must not be empty" if kind == "string_too_short" and count == 1 else (
            f"must have {'at least' if kind == 'string_too_short' else 'at most'} {count} characters")
        return what + ("" if kind == "string_too_short" else f", got {len(str(value)):,}")
    if kind == "string_pattern_mismatch":
        if ctx.get("pattern") == r"^\S+$":
            return f"must be one word without spaces, got {_show(value)}"
        return f"{_show(value)} does not have the expected form"
    if kind == "literal_error":
        return f"must be one of {ctx.get('expected', '?').replace(' or ', ', ')}, got {_show(value)}"
    if kind == "union_tag_invalid":
        return (f"{ctx.get('discriminator', 'kind')} {ctx.get('tag')!r} is not one of "
                f"{ctx.get('expected_tags', '?')}")
    if kind == "union_tag_not_found":
        return f"say which kind it is with {ctx.get('discriminator', 'a kind key')}"
    if kind == "extra_forbidden":
        return "unknown key"
    return str(error["msg"]).removeprefix("Value error, ")


def _clean_loc(data: Any, loc: tuple[Any, ...]) -> KeyPath:
    """pydantic's location -> the key path in the file (drop validator and union-tag parts, map
    ``x``/``y``/``theta`` of a pose written as a list to its index)."""
    path: list[str | int] = []
    current = data
    parts = [p for p in loc if not (isinstance(p, str) and ("function-" in p or p.startswith("tagged-union")))]
    for index, part in enumerate(parts):
        last = index == len(parts) - 1
        if isinstance(current, dict):
            if part in current:
                path.append(part)
                current = current[part]
            elif last or not isinstance(part, str):
                path.append(part)
            continue  # a union tag or a model name: not in the file
        if isinstance(current, list):
            if isinstance(part, str) and part in ("x", "y", "theta"):
                part = ("x", "y", "theta").index(part)
            if isinstance(part, int) and part < len(current):
                path.append(part)
                current = current[part]
                continue
            if isinstance(part, int):
                path.append(part)
            break
        break  # a scalar: nothing below it
    return tuple(path)


def _models_at(tp: Any, parts: list[Any], depth: int = 0) -> list[type[BaseModel]]:
    """The models a pydantic location may point into (to suggest a misspelt key's right name)."""
    import types
    import typing

    if depth > 32:
        return []
    while typing.get_origin(tp) is typing.Annotated:
        tp = typing.get_args(tp)[0]
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        found: list[type[BaseModel]] = []
        for member in typing.get_args(tp):
            found += _models_at(member, parts, depth + 1)
            if parts:
                found += _models_at(member, parts[1:], depth + 1)  # a union's tag in the location
        return found
    if not parts:
        return [tp] if isinstance(tp, type) and issubclass(tp, BaseModel) else []
    part, rest = parts[0], parts[1:]
    if isinstance(tp, type) and issubclass(tp, BaseModel):
        info = tp.model_fields.get(part) if isinstance(part, str) else None
        return _models_at(info.annotation, rest, depth + 1) if info is not None else []
    if origin in (list, tuple, dict) and typing.get_args(tp):
        return _models_at(typing.get_args(tp)[-1], rest, depth + 1)
    return []


def validate_located(model: type[M], located: LocatedYaml, base: KeyPath = ()) -> M:
    """Validate with pydantic; report the most useful error at its line in the source file.

    A misspelt key shows up twice in pydantic's list (``robto``: extra, ``robot``: missing);
    the unknown key is the cause, so it is reported first, with the closest allowed key."""
    data = located.data
    for part in base:
        data = data[part]
    try:
        return model.model_validate(data)
    except ValidationError as exc:
        errors = exc.errors()
        extra = [e for e in errors if e["type"] == "extra_forbidden"]
        chosen = extra[0] if extra else errors[0]
        path = (*base, *_clean_loc(data, tuple(chosen["loc"])))
        if chosen["type"] == "extra_forbidden":
            parent = path[:-1]
            missing = [str(e["loc"][-1]) for e in errors if e["type"] == "missing"
                       and (*base, *_clean_loc(data, tuple(e["loc"][:-1]))) == parent]
            allowed = [name for found in _models_at(model, list(chosen["loc"][:-1]))
                       for name in found.model_fields]
            key = str(path[-1])
            close = (difflib.get_close_matches(key, missing, n=1, cutoff=0.5)
                     or difflib.get_close_matches(key, allowed, n=1, cutoff=0.6))
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise located.error(path, f"unknown key {key!r}{hint}") from None
        raise located.error(path, user_message(chosen)) from None


def as_date(value: Any) -> dt.date:
    """Helper for models: a YAML date (already checked by the reader) or ISO text -> date."""
    if isinstance(value, dt.datetime):
        return value.date()
    if isinstance(value, dt.date):
        return value
    if isinstance(value, str):
        try:
            return dt.date.fromisoformat(value.strip())
        except ValueError:
            raise ValueError(_describe_date_error(value)) from None
    raise ValueError(f"expected a date such as 2026-11-25, got {_show(value)}")
