"""YAML loading that remembers where every value came from.

Why: a care-home technician editing a scene or agenda file needs errors that say
``scenes/center_a.yaml:42:7: objects[2].pose: ...``, not a pydantic dump.  PyYAML's composer
keeps marks on each node; we walk the node tree once and record the line/column of every key
path so validation errors can be mapped back to the file.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

import yaml
from pydantic import BaseModel, ValidationError

KeyPath = tuple[str | int, ...]
M = TypeVar("M", bound=BaseModel)


@dataclass(frozen=True)
class SourceError(Exception):
    """An input-file error a person can act on: file, line, column, key path and message."""

    file: str
    line: int
    column: int
    key: str
    message: str

    def __str__(self) -> str:
        where = f"{self.file}:{self.line}:{self.column}"
        return f"{where}: {self.key}: {self.message}" if self.key else f"{where}: {self.message}"


@dataclass(frozen=True)
class LocatedYaml:
    """Plain Python data plus the (line, column) of each key path, both 1-based."""

    data: Any
    marks: dict[KeyPath, tuple[int, int]]
    file: str

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


def format_key(path: KeyPath) -> str:
    text = ""
    for part in path:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text


def _walk(node: yaml.Node, path: KeyPath, marks: dict[KeyPath, tuple[int, int]]) -> None:
    marks[path] = (node.start_mark.line + 1, node.start_mark.column + 1)
    if isinstance(node, yaml.MappingNode):
        for key_node, value_node in node.value:
            key = key_node.value
            _walk(value_node, (*path, key), marks)
            # Point a key's errors at the key itself, which is where people look.
            marks[(*path, key)] = (key_node.start_mark.line + 1, key_node.start_mark.column + 1)
    elif isinstance(node, yaml.SequenceNode):
        for index, item in enumerate(node.value):
            _walk(item, (*path, index), marks)


def load_located(text: str, file: str) -> LocatedYaml:
    """Parse YAML text; syntax errors become SourceError with the parser's own position."""
    loader: yaml.SafeLoader | None = None
    try:
        loader = yaml.SafeLoader(text)  # the reader already refuses control characters here
        # One parse: compose the node tree (it keeps the marks), then build plain data from it.
        node = loader.get_single_node()
        data = loader.construct_document(node) if node is not None else None
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line, column = (mark.line + 1, mark.column + 1) if mark else (1, 1)
        raise SourceError(file, line, column, "", f"YAML syntax error: {exc.problem}") from None
    except yaml.reader.ReaderError as exc:
        line = text.count("\n", 0, exc.position) + 1
        column = exc.position - (text.rfind("\n", 0, exc.position) + 1) + 1
        raise SourceError(file, line, column, "", f"control character U+{exc.character:04X} is not allowed in YAML") from None
    except yaml.YAMLError as exc:
        raise SourceError(file, 1, 1, "", f"YAML error: {exc}") from None
    finally:
        if loader is not None:
            loader.dispose()
    marks: dict[KeyPath, tuple[int, int]] = {}
    if node is not None:
        _walk(node, (), marks)
    return LocatedYaml(data=data, marks=marks, file=file)


def load_located_file(path: str | Path) -> LocatedYaml:
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise SourceError(str(path), 1, 1, "", f"cannot read file: {exc.strerror}") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        column = exc.start - (data.rfind(b"\n", 0, exc.start) + 1) + 1
        raise SourceError(str(path), line, column, "", f"not UTF-8 text (byte 0x{data[exc.start]:02x}); "
                          "save the file as UTF-8") from None
    return load_located(text, str(path))


def validate_located(model: type[M], located: LocatedYaml, base: KeyPath = ()) -> M:
    """Validate with pydantic; report the FIRST error at its line in the source file."""
    data = located.data
    for part in base:
        data = data[part]
    try:
        return model.model_validate(data)
    except ValidationError as exc:
        first = exc.errors()[0]
        loc = tuple(p for p in first["loc"] if not (isinstance(p, str) and p.startswith("function-")))
        raise located.error((*base, *loc), first["msg"]) from None
