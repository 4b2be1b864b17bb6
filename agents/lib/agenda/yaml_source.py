"""Agenda activities written in YAML: a standalone file (``activities: [...]``) or a scene's ``agenda:``.

Why we walk PyYAML's composed nodes instead of ``safe_load``: the nodes keep line numbers, so an
error says ``agenda.yaml:14: activities[2].start: ...``; and scalars stay the text staff typed,
so an unquoted ``start: 11:00`` is read as "11:00", not as the YAML 1.1 sexagesimal number 660.

Also here: :func:`load_agenda_file`, which picks the reader by file suffix, because scenes
reference agenda files of either format.
"""

from __future__ import annotations

import difflib
from pathlib import Path
from typing import Any

import yaml
from pydantic import ValidationError

from agents.lib.agenda.ics_source import IcsAgenda, load_ics_file, parse_ics
from agents.lib.agenda.model import ActivitySpec, AgendaSourceError, SourceProblem

_NULL_TAG = "tag:yaml.org,2002:null"
SPEC_KEYS: tuple[str, ...] = tuple(k for k in ActivitySpec.model_fields if k != "source")


def _line(node: yaml.Node) -> int:
    return node.start_mark.line + 1


def _plain(node: yaml.Node, file: str, key: str, problems: list[SourceProblem]) -> Any:
    """A value node -> the text as typed (None for null), or a list of such texts."""
    if isinstance(node, yaml.ScalarNode):
        return None if node.tag == _NULL_TAG else node.value
    if isinstance(node, yaml.SequenceNode):
        items = []
        for index, item in enumerate(node.value):
            if not isinstance(item, yaml.ScalarNode):
                problems.append(SourceProblem(file, _line(item), "expected a plain value",
                                              f"{key}[{index}]"))
                continue
            items.append(None if item.tag == _NULL_TAG else item.value)
        return items
    problems.append(SourceProblem(file, _line(node), "expected a value or a list, not a mapping", key))
    return None


def _message(error: dict[str, Any]) -> str:
    if error["type"] == "missing":
        return "required key is missing"
    message = str(error["msg"])
    return message.removeprefix("Value error, ")


def _activity(node: yaml.Node, file: str, path: str, problems: list[SourceProblem]) -> ActivitySpec | None:
    if not isinstance(node, yaml.MappingNode):
        problems.append(SourceProblem(file, _line(node), "an activity must be a mapping such as "
                                      "{name: ..., object: ..., start: \"11:00\", end: \"12:00\"}", path))
        return None
    before = len(problems)
    data: dict[str, Any] = {}
    lines: dict[str, tuple[int, yaml.Node]] = {}
    for key_node, value_node in node.value:
        key = str(key_node.value)
        if key in lines:
            problems.append(SourceProblem(file, _line(key_node), f"duplicate key (first on line "
                                          f"{lines[key][0]})", f"{path}.{key}"))
            continue
        lines[key] = (_line(key_node), value_node)
        if key not in SPEC_KEYS:
            close = difflib.get_close_matches(key, SPEC_KEYS, n=1)
            hint = f"did you mean {close[0]!r}? " if close else ""
            problems.append(SourceProblem(file, _line(key_node), f"unknown key; {hint}allowed keys: "
                                          f"{', '.join(SPEC_KEYS)}", f"{path}.{key}"))
            continue
        data[key] = _plain(value_node, file, f"{path}.{key}", problems)
    if len(problems) > before:
        return None
    data["source"] = f"{file}:{_line(node)}"
    try:
        return ActivitySpec.model_validate(data)
    except ValidationError as exc:
        for error in exc.errors():
            loc = error["loc"]
            key = str(loc[0]) if loc else ""
            line = _line(node)
            if key in lines:
                line, value_node = lines[key]
                if len(loc) > 1 and isinstance(loc[1], int) and isinstance(value_node, yaml.SequenceNode):
                    line = _line(value_node.value[loc[1]])
            label = f"{path}.{key}" + (f"[{loc[1]}]" if len(loc) > 1 else "") if key else path
            problems.append(SourceProblem(file, line, _message(error), label))
        return None


def specs_from_node(node: yaml.Node | None, file: str, path: str = "activities") -> list[ActivitySpec]:
    """A YAML sequence of activity mappings -> specs; every problem is reported, with its line."""
    if node is None or (isinstance(node, yaml.ScalarNode) and node.tag == _NULL_TAG):
        return []
    if not isinstance(node, yaml.SequenceNode):
        raise AgendaSourceError([SourceProblem(file, _line(node), "expected a list of activities "
                                               "(each line starting with '- ')", path)])
    problems: list[SourceProblem] = []
    specs = [_activity(item, file, f"{path}[{index}]", problems) for index, item in enumerate(node.value)]
    if problems:
        raise AgendaSourceError(problems)
    return [spec for spec in specs if spec is not None]


def _compose(text: str, file: str) -> yaml.Node | None:
    try:
        return yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line = mark.line + 1 if mark is not None else None
        raise AgendaSourceError([SourceProblem(file, line, f"YAML syntax error: {exc.problem}")]) from None
    except yaml.YAMLError as exc:
        raise AgendaSourceError([SourceProblem(file, None, f"YAML error: {exc}")]) from None


def _mapping_value(root: yaml.MappingNode, key: str) -> yaml.Node | None:
    return next((value for k, value in root.value if k.value == key), None)


def parse_yaml_agenda(text: str, file: str) -> list[ActivitySpec]:
    """A standalone agenda file: a mapping with one key ``activities`` holding the list."""
    root = _compose(text, file)
    if root is None:
        return []
    if not isinstance(root, yaml.MappingNode):
        raise AgendaSourceError([SourceProblem(file, _line(root), "an agenda file is a mapping with "
                                               "one key, 'activities:', holding the list")])
    for key_node, _ in root.value:
        if key_node.value != "activities":
            raise AgendaSourceError([SourceProblem(
                file, _line(key_node), "unknown top-level key; an agenda file has only 'activities:'",
                str(key_node.value))])
    return specs_from_node(_mapping_value(root, "activities"), file, "activities")


def _read_text(path: Path) -> str:
    try:
        return path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        reason = exc.strerror if isinstance(exc, OSError) else "not UTF-8 text"
        raise AgendaSourceError([SourceProblem(str(path), None, f"cannot read file: {reason}")]) from None


def load_yaml_file(path: str | Path) -> list[ActivitySpec]:
    path = Path(path)
    return parse_yaml_agenda(_read_text(path), str(path))


def load_agenda_file(path: str | Path) -> list[ActivitySpec | IcsAgenda]:
    """Read an agenda file of either format, chosen by suffix (.ics, .yaml, .yml)."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".ics":
        return [load_ics_file(path)]
    if suffix in (".yaml", ".yml"):
        return list(load_yaml_file(path))
    raise AgendaSourceError([SourceProblem(str(path), None, "unknown agenda format: use a .ics "
                                           "(iCalendar) or a .yaml file")])


def parse_agenda_text(text: str, fmt: str, source: str) -> list[ActivitySpec | IcsAgenda]:
    """Agenda content received as text (e.g. by `chronav agenda load` over Zenoh)."""
    if fmt == "ics":
        return [parse_ics(text, source)]
    if fmt == "yaml":
        return list(parse_yaml_agenda(text, source))
    raise AgendaSourceError([SourceProblem(source, None,
                                           f"unknown agenda format {fmt!r}: use 'ics' or 'yaml'")])


def load_scene_agenda(scene_path: str | Path) -> list[ActivitySpec | IcsAgenda]:
    """The agenda of a scene: its ``agenda:`` list plus its ``agenda_file`` (relative to the scene).

    Read from the scene's own nodes so errors name the scene file and line; the scene schema
    itself (scenes/model.py) is checked by the scene loader, not here.
    """
    scene_path = Path(scene_path)
    file = str(scene_path)
    root = _compose(_read_text(scene_path), file)
    if not isinstance(root, yaml.MappingNode):
        return []
    sources: list[ActivitySpec | IcsAgenda] = list(
        specs_from_node(_mapping_value(root, "agenda"), file, "agenda"))
    ref = _mapping_value(root, "agenda_file")
    if isinstance(ref, yaml.ScalarNode) and ref.tag != _NULL_TAG:
        target = Path(ref.value)
        target = target if target.is_absolute() else scene_path.parent / target
        if not target.exists():
            raise AgendaSourceError([SourceProblem(file, _line(ref), f"agenda file {ref.value!r} not found "
                                                   f"(looked for {target})", "agenda_file")])
        sources.extend(load_agenda_file(target))
    return sources
