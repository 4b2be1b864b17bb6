"""The README is part of the product: its DSR example runs and its commands exist."""

from __future__ import annotations

import contextlib
import io
import re

import pytest
from typer.testing import CliRunner

from tests.support import REPO_ROOT
from tools.cli import app

README = (REPO_ROOT / "README.md").read_text()


def test_dsr_example_runs_and_prints_what_it_says() -> None:
    section = README[README.index("## The DSR"):]
    code = re.search(r"```python\n(.*?)```", section, re.S)
    assert code is not None
    lines = code.group(1).strip().splitlines()
    assert len(lines) == 5, "the README promises a five-line example"
    expected = lines[-1].split("#", 1)[1].strip()
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code.group(1), "README.md", "exec"), {})
    assert out.getvalue().strip() == expected


COMMANDS = sorted(set(re.findall(r"^\| `chronav ([a-z]+)(?: ([a-z][a-z-]*))?", README, re.M)))


@pytest.mark.parametrize(("group", "sub"), COMMANDS)
def test_every_documented_command_exists(group: str, sub: str) -> None:
    args = [group, *([sub] if sub else []), "--help"]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output


def test_two_setup_commands() -> None:
    assert "make demo" in README and "make test" in README
    makefile = (REPO_ROOT / "Makefile").read_text()
    assert re.search(r"^demo:", makefile, re.M) and re.search(r"^test:", makefile, re.M)


def test_first_session_agenda_change_is_accepted_on_center_day() -> None:
    """The README's first session adds an activity to center_day: the agenda agent must accept it."""
    import json
    import shlex

    from agents.lib.agenda.changes import apply_change, parse_change
    from agents.world.scene_world import load_world
    from tools.agenda import add_change, split_participants

    section = README[README.index("## A first session"):README.index("## Watching a run in Rerun")]
    assert "chronav launch center_day" in section and "chronav agenda watch" in section
    line = next(ln for ln in section.splitlines() if "chronav agenda add" in ln)
    args = shlex.split(line.split("#")[0])[3:]
    obj, start, end = args[:3]
    options = dict(zip(args[3::2], args[4::2]))
    world = load_world(REPO_ROOT / "scenes" / "center_day.yaml")
    change = add_change(obj, start, end, name=options["--name"],
                        participants=split_participants(options["--participants"]))
    day = apply_change(world.agenda, parse_change(json.dumps(change)), known_objects=world.object_names,
                       known_rooms=world.room_names, known_people=world.person_names)
    added = next(a for a in day.activities if a.name == options["--name"])
    assert not [a for a in world.agenda.activities
                if a.object == obj and a.start_s < added.end_s and added.start_s < a.end_s], "a free slot"
