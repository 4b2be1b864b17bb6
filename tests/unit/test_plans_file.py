"""<run>/plans.jsonl: a run keeps every path its navigation adopted (issue 42, point 5), and
reads it back as a person-given file."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from agents.world.plans_file import PLANS_FILE, PlansWriter, read_plans
from scenes.errors import SourceError
from tests.support import REPO_ROOT
from tools.cli import app

TINY = REPO_ROOT / "tests" / "data" / "eval_tiny.yaml"


def test_a_run_keeps_the_plans_it_adopted(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("CHRONAV_RUNS", str(tmp_path))
    result = CliRunner().invoke(app, ["launch", str(TINY), "--in-process", "--json", "--no-record"])
    assert result.exit_code == 0, result.output
    run_dir = Path(json.loads(result.stdout)["run_dir"])
    plans = read_plans(run_dir / PLANS_FILE)
    assert plans, "the navigation adopted no path"
    times = [float(line.split(",")[0]) for line in (run_dir / "trajectory.csv").read_text().splitlines()[1:]]
    first = plans[0]
    assert times[0] - 1.0 <= first.t_s <= times[0] + 1.0      # adopted when the robot set off
    assert len(first.x) == len(first.y) >= 2 and first.reason
    assert [p.t_s for p in plans] == sorted(p.t_s for p in plans)


def test_written_plans_read_back(tmp_path: Path) -> None:
    writer = PlansWriter(tmp_path)
    writer.adopted(36_000.0, [0.0, 1.0], [0.0, 1.5], 3.0, "new goal")
    writer.close()
    (plan,) = read_plans(tmp_path / PLANS_FILE)
    assert (plan.t_s, plan.x, plan.y, plan.cost, plan.reason) == (36_000.0, (0.0, 1.0), (0.0, 1.5), 3.0, "new goal")
    PlansWriter(None).adopted(1.0, [0.0], [0.0], 1.0, "no run directory: nothing written")


@pytest.mark.parametrize(("line", "key"), [('{"t_s": 1.0, "x": [1e308], "y": [0.0]}', "x"),
                                           ('{"t_s": -1.0, "x": [0.0], "y": [0.0]}', "t_s"),
                                           ('{"t_s": 1.0, "x": [0.0, 1.0], "y": [0.0]}', "y"),
                                           ('{"t_s": 1.0, "x": [], "y": []}', "x"),
                                           ('{"t_s": 1.0, "x": [NaN], "y": [0.0]}', "x"),
                                           ('[1, 2]', ""), ("not json", ""), ("[" * 100_000, ""),
                                           ('{"t_s": 1.0, "x": [' + "9" * 5000 + '], "y": [0.0]}', "")])
def test_a_bad_line_is_an_error_naming_file_line_and_key(tmp_path: Path, line: str, key: str) -> None:
    path = tmp_path / PLANS_FILE
    path.write_text('{"t_s": 1.0, "x": [0.0], "y": [0.0]}\n\n' + line + "\n")
    with pytest.raises(SourceError) as caught:
        read_plans(path)
    assert (caught.value.line, caught.value.key) == (3, key)
    assert str(path) in str(caught.value)


def test_a_run_directory_that_cannot_be_written_does_not_stop_the_navigation(tmp_path: Path) -> None:
    PlansWriter(tmp_path / "missing" / "run").adopted(1.0, [0.0], [0.0], 1.0, "not kept")   # logged, no raise
    full = PlansWriter(None)
    full._handle = open("/dev/full", "w", encoding="utf-8", buffering=1)  # noqa: SIM115 - a disk that is full
    full.adopted(1.0, [0.0], [0.0], 1.0, "not kept")
    assert full._handle is None                         # given up after the first failed write
    full.adopted(2.0, [0.0], [0.0], 1.0, "given up")
