"""tools/code_health.py on a tiny tree whose numbers are known by construction."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tools import code_health

LONG = "def long_one(x):\n" + "".join(f"    x += {i}\n" for i in range(30)) + "    return x\n"
BIG = "class Big:\n" + "".join(f"    def m{i}(self):\n        return {i}\n" for i in range(21))
SMALL = "class Small:\n" + "".join(f"    def m{i}(self):\n        return {i}\n" for i in range(20))


@pytest.fixture
def tree(tmp_path: Path) -> Path:
    pkg = tmp_path / "hpkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "a.py").write_text(
        "from typing import Any\n\nimport hpkg.b  # noqa: F401 - cycle on purpose\n\n"
        "TEXT = '# noqa inside a string is not a comment'\n\n"
        "def read(graph: Any, key: str) -> Any:\n    return graph  # type: ignore[return-value]\n\n"
        "def other(g: 'Any', store_graph: dict[str, Any]) -> None:\n    pass\n\n" + LONG)
    (pkg / "b.py").write_text("import hpkg.a\n\n" + BIG + "\n" + SMALL)
    (pkg / "c.py").write_text("from typing import TYPE_CHECKING\n\nif TYPE_CHECKING:\n    import hpkg.d\n")
    (pkg / "d.py").write_text("import hpkg.c\n")
    tests = tmp_path / "tests"
    tests.mkdir()
    (tests / "test_x.py").write_text("import os  # noqa: F401\nx = 1  # type: ignore\n" + LONG.replace("long_one", "not_counted"))
    (tmp_path / ".venv").mkdir()
    (tmp_path / ".venv" / "skipped.py").write_text("y = 1  # noqa\n")
    return tmp_path


def test_the_numbers_of_a_known_tree(tree: Path) -> None:
    health = code_health.measure(tree, ["hpkg"], with_duplicates=False)
    assert health.files == 6                      # .venv left out
    assert health.noqa == 2 and health.noqa_by_folder == {"hpkg": 1, "tests": 1}
    assert health.type_ignore == 2 and health.type_ignore_by_folder == {"hpkg": 1, "tests": 1}
    # read: graph + return; other: g (a string annotation) and store_graph's dict[str, Any]
    assert health.any_in_signatures == 4
    assert health.graph_any == 2                  # `graph` and `g`; store_graph is a dict that holds Any
    assert health.longest_functions[0] == "hpkg/a.py:long_one:32"
    assert all("not_counted" not in f for f in health.longest_functions)   # tests are not the packages
    assert health.classes_over_20_methods == ["hpkg/b.py:Big:21"]
    # a <-> b import each other at run time; c -> d only under TYPE_CHECKING, so no cycle there
    assert health.import_cycles == [["hpkg.a", "hpkg.b"]]


def test_the_command_prints_one_json_object(tree: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert code_health.main(["--root", str(tree), "--packages", "hpkg", "--json", "--no-duplicates"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["noqa"] == 2 and out["import_cycles"] == [["hpkg.a", "hpkg.b"]]
    assert out["duplicates"] is None and out["duplicates_note"] == "not measured"


def test_without_the_duplicates_command_the_count_is_null_with_the_reason(
        tree: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("PATH", str(tree))
    count, note = code_health.duplicate_pairs(tree)
    assert count is None and "not on PATH" in note


def test_a_missing_root_is_an_error_that_says_what_to_do(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert code_health.main(["--root", str(tmp_path / "nowhere")]) == 2
    assert "pass --root DIR" in capsys.readouterr().err
