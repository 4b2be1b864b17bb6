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
