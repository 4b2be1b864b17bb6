"""Agenda activities written in YAML: a standalone file (``activities: [...]``) or a scene's ``agenda:``.

Why through ``scenes/yamlio.py``: it is chronav's one YAML reader (bounded depth, aliases and
sizes; duplicate keys refused; a byte-order mark accepted) and its one located error type,
``SourceError``.  The agenda reads the activities as the text staff typed (``text_data``), so an
unquoted ``start: 11:00`` is "11:00" and ``name: 123`` is the name "123".  Unlike a scene, an
agenda reports *every* problem at once (``AgendaSourceError`` holds them all): staff fix a file in
one go.

Also here: :func:`load_agenda_file`, which picks the reader by file suffix, because scenes
reference agenda files of either format.
"""

from __future__ import annotations

import difflib
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from agents.lib.agenda.ics_source import IcsAgenda, load_ics_file, parse_ics
from agents.lib.agenda.model import ActivitySpec, AgendaSourceError
from scenes.limits import YAML_BYTES
from scenes.yamlio import (KeyPath, LocatedYaml, SourceError, load_located, load_located_file, read_text_file,
                           user_message)

SPEC_KEYS: tuple[str, ...] = tuple(k for k in ActivitySpec.model_fields if k != "source")
_EXAMPLE = '{name: ..., object: ..., start: "11:00", end: "12:00"}'


def _plain(value: Any, located: LocatedYaml, path: KeyPath, problems: list[SourceError]) -> Any:
    """A value -> the text as typed (None for null), or a list of such texts."""
    if value is None or isinstance(value, str):
        return value
    if isinstance(value, list):
        items = []
        for index, item in enumerate(value):
            if item is not None and not isinstance(item, str):
                problems.append(located.error((*path, index), "expected a plain value, not a list or a mapping"))
                continue
            items.append(item)
        return items
    problems.append(located.error(path, "expected a value or a list, not a mapping"))
    return None


def _activity(item: Any, located: LocatedYaml, path: KeyPath, problems: list[SourceError]) -> ActivitySpec | None:
    if not isinstance(item, dict):
        problems.append(located.error(path, f"an activity must be a mapping such as {_EXAMPLE}"))
        return None
    before = len(problems)
    data: dict[str, Any] = {}
    for key, value in item.items():
        if key not in SPEC_KEYS:
            close = difflib.get_close_matches(str(key), SPEC_KEYS, n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            problems.append(located.error((*path, key), f"unknown key {str(key)!r}{hint}; allowed keys: "
                                          f"{', '.join(SPEC_KEYS)}"))
            continue
        data[key] = _plain(value, located, (*path, key), problems)
    if len(problems) > before:
        return None
    line, _ = located.where(path)
    data["source"] = f"{located.file}:{line}"
    try:
        return ActivitySpec.model_validate(data)
    except ValidationError as exc:
        for error in exc.errors():
            loc = tuple(p for p in error["loc"] if not (isinstance(p, str) and "function-" in p))
            problems.append(located.error((*path, *loc), user_message(error)))
        return None


def specs_from_located(located: LocatedYaml, path: KeyPath) -> list[ActivitySpec]:
    """The YAML sequence of activity mappings at ``path`` -> specs; every problem is reported, with its line."""
    value = located.text_data(path)
    if value is None:
        return []
    if not isinstance(value, list):
        raise AgendaSourceError([located.error(path, "expected a list of activities (each line starting "
                                               "with '- ')")])
    problems: list[SourceError] = []
    specs = [_activity(item, located, (*path, index), problems) for index, item in enumerate(value)]
    if problems:
        raise AgendaSourceError(problems)
    return [spec for spec in specs if spec is not None]


def _located(text: str, file: str) -> LocatedYaml:
    try:
        return load_located(text, file)
    except SourceError as exc:
        raise AgendaSourceError([exc]) from None


def parse_yaml_agenda(text: str, file: str) -> list[ActivitySpec]:
    """A standalone agenda file: a mapping with one key ``activities`` holding the list."""
    located = _located(text, file)
    if located.data is None:
        return []
    if not isinstance(located.data, dict):
        raise AgendaSourceError([located.error((), "an agenda file is a mapping with one key, "
                                               "'activities:', holding the list")])
    for key in located.data:
        if key != "activities":
            close = difflib.get_close_matches(str(key), ["activities"], n=1)
            hint = " (did you mean 'activities'?)" if close else ""
            raise AgendaSourceError([located.error((key,), f"unknown top-level key {str(key)!r}{hint}; an "
                                                   "agenda file has only 'activities:'")])
    return specs_from_located(located, ("activities",))


def load_yaml_file(path: str | Path) -> list[ActivitySpec]:
    path = Path(path)
    try:
        text = read_text_file(path, max_bytes=YAML_BYTES.value(), limit_env=YAML_BYTES.env, what="YAML file")
    except SourceError as exc:
        raise AgendaSourceError([exc]) from None
    return parse_yaml_agenda(text, str(path))


def load_agenda_file(path: str | Path) -> list[ActivitySpec | IcsAgenda]:
    """Read an agenda file of either format, chosen by suffix (.ics, .yaml, .yml)."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix in (".ics", ".ical"):
        return [load_ics_file(path)]
    if suffix in (".yaml", ".yml"):
        return list(load_yaml_file(path))
    raise AgendaSourceError([SourceError(str(path), None, None, "", "unknown agenda format: use a .ics "
                                         "(iCalendar) or a .yaml file")])


def parse_agenda_text(text: str, fmt: str, source: str) -> list[ActivitySpec | IcsAgenda]:
    """Agenda content received as text (e.g. by `chronav agenda load` over Zenoh)."""
    if fmt == "ics":
        return [parse_ics(text, source)]
    if fmt == "yaml":
        return list(parse_yaml_agenda(text, source))
    raise AgendaSourceError([SourceError(source, None, None, "",
                                         f"unknown agenda format {fmt!r}: use 'ics' or 'yaml'")])


def scene_agenda(located: LocatedYaml, scene_dir: Path) -> list[ActivitySpec | IcsAgenda]:
    """The agenda of a scene already read: its ``agenda:`` list plus its ``agenda_file`` (relative to
    the scene's folder).  Errors name the scene file and line; the scene schema itself is checked by
    the scene loader (scenes/loader.py), not here."""
    if not isinstance(located.data, dict):
        return []
    sources: list[ActivitySpec | IcsAgenda] = list(specs_from_located(located, ("agenda",)))
    ref = located.text_data(("agenda_file",))
    if isinstance(ref, str):
        target = Path(ref)
        target = target if target.is_absolute() else scene_dir / target
        if not target.exists():
            raise AgendaSourceError([located.error(("agenda_file",), f"agenda file {ref!r} not found "
                                                   f"(looked for {target})")])
        try:   # a FIFO or a directory is refused as such (scenes/files.py), not "not found"
            sources.extend(load_agenda_file(target))
        except AgendaSourceError as exc:
            problem = exc.problems[0]
            if problem.line is None:   # the file as a whole: say which key of the scene named it
                raise AgendaSourceError([located.error(("agenda_file",), f"agenda file {ref!r}: {problem.message}")]) \
                    from None
            raise
    return sources


def load_scene_agenda(scene_path: str | Path) -> list[ActivitySpec | IcsAgenda]:
    """The agenda of a scene file (see :func:`scene_agenda`)."""
    scene_path = Path(scene_path)
    try:
        located = load_located_file(scene_path)
    except SourceError as exc:
        raise AgendaSourceError([exc]) from None
    return scene_agenda(located, scene_path.parent)

