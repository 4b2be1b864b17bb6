"""Issue 39: every run leaves each mission's slices, and a finished run is measured per mission
without running it again (`chronav report`, `chronav metrics RUN --mission M`), people included.

One in-process run of tests/data/eval_walkers.yaml (a visitor walks across the lounge against the
robot) is shared by the module: the user's path is `chronav launch --in-process`, then the commands
through typer's CliRunner.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

from agents.lib.metrics.metric_catalog import column_label
from agents.lib.metrics.metrics import flatten, read_trajectory_csv
from tests.support import REPO_ROOT
from tools.cli import app

WALKERS = REPO_ROOT / "tests" / "data" / "eval_walkers.yaml"


@pytest.fixture(scope="module")
def runs_dir(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """$CHRONAV_RUNS of the module, holding one finished in-process run of eval_walkers."""
    directory = tmp_path_factory.mktemp("runs")
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("CHRONAV_RUNS", str(directory))
        patch.setenv("RERUN", "off")
        result = CliRunner().invoke(app, ["launch", str(WALKERS), "--in-process", "--no-record", "--json"])
        assert result.exit_code == 0, result.output
        assert json.loads(result.stdout)["missions"]["cross"]["state"] == "done"
        yield directory


@pytest.fixture()
def run_dir(runs_dir: Path) -> Path:
    (found,) = [p for p in runs_dir.iterdir() if (p / "result.json").exists()]
    return found


def _invoke(args: list[str], **env: str) -> Any:
    return CliRunner().invoke(app, args, env=env or None)


def test_a_run_leaves_each_missions_robot_and_people_slices(run_dir: Path) -> None:
    result = json.loads((run_dir / "result.json").read_text())
    mission = result["missions"]["cross"]
    started, finished = mission["started_s"], mission["finished_s"]
    robot = read_trajectory_csv(run_dir / "missions" / "cross.csv")
    whole = read_trajectory_csv(run_dir / "trajectory.csv")
    inside = whole[(whole[:, 0] >= started - 1e-6) & (whole[:, 0] <= finished + 1e-6)]
    assert len(robot) >= 50 and np.array_equal(robot, inside)
    header, *lines = (run_dir / "people.csv").read_text().splitlines()
    expected = [header, *(line for line in lines if started - 1e-6 <= float(line.split(",")[0]) <= finished + 1e-6)]
    assert (run_dir / "missions" / "cross.people.csv").read_text().splitlines() == expected
    assert any(",visitor," in line for line in expected[1:]), "the walking visitor is in the mission's slice"
    info = json.loads((run_dir / "missions" / "cross.json").read_text())
    assert (info["goal_xy"], info["started_s"], info["finished_s"]) == ([5.2, 1.2], started, finished)


def test_the_launchers_result_writer_cuts_the_slices_of_any_run(run_dir: Path, tmp_path: Path) -> None:
    """A launch, a ROS robot's run and an in-process run all end in `_write_result`: it cuts the slices."""
    from tools.launch import RunResult, _write_result

    other = tmp_path / "launched"
    other.mkdir()
    for name in ("trajectory.csv", "people.csv"):
        shutil.copy(run_dir / name, other / name)
    missions = json.loads((run_dir / "result.json").read_text())["missions"]
    missions["later"] = {"mission_id": "later", "state": "pending", "time_s": 37000.0}   # never started: no slice
    _write_result(RunResult(scene="eval_walkers", run_dir=other, rrd_path=None, missions=missions, events=[],
                            restarts={}, wall_s=1.0, scene_path=WALKERS))
    assert sorted(p.name for p in (other / "missions").iterdir()) == ["cross.csv", "cross.json", "cross.people.csv"]
    assert (other / "missions" / "cross.people.csv").read_bytes() == (run_dir / "missions" / "cross.people.csv").read_bytes()


def test_metrics_of_a_slice_a_run_and_latest_are_one_measurement_with_the_people(run_dir: Path) -> None:
    by_csv = _invoke(["metrics", str(WALKERS), str(run_dir / "missions" / "cross.csv"), "--json"])
    by_run = _invoke(["metrics", str(run_dir), "--mission", "cross", "--json"])
    by_latest = _invoke(["metrics", str(WALKERS), "latest", "--mission", "cross", "--json"],
                        CHRONAV_RUNS=str(run_dir.parent))
    outputs = []
    for result in (by_csv, by_run, by_latest):
        assert result.exit_code == 0, result.output
        outputs.append(json.loads(result.stdout))
    assert outputs[0] == outputs[1] == outputs[2]
    report = outputs[0]
    assert report["people"] == str(run_dir / "missions" / "cross.people.csv")
    mission = json.loads((run_dir / "result.json").read_text())["missions"]["cross"]
    assert report["at_s"] == mission["started_s"]
    dynamic = report["metrics"]["dynamic"]
    assert dynamic["completed"] is True and dynamic["min_distance_to_people_m"] < 3.0


@pytest.mark.parametrize(("args", "words"), [
    (["metrics", "{run}", "--mission", "nope"], "its missions: cross"),
    (["metrics", "{run}"], "pick a mission with --mission M; its missions: cross"),
    (["report", "{run}", "--mission", "nope"], "its missions: cross"),
    (["report", "no-such-run"], "no such run"),
    (["metrics", "eval_walkers"], "no trajectory given"),
])
def test_bad_run_or_mission_is_one_line_naming_what_there_is(run_dir: Path, args: list[str], words: str) -> None:
    result = _invoke([a.format(run=run_dir) for a in args])
    assert result.exit_code == 2, result.output
    assert words in result.stderr and "Traceback" not in result.output
    assert len(result.stderr.strip().splitlines()) == 1


def test_report_of_a_finished_run_is_the_metrics_of_its_slices_and_the_baseline(run_dir: Path) -> None:
    result = _invoke(["report", "latest", "--json"], CHRONAV_RUNS=str(run_dir.parent))
    assert result.exit_code == 0, result.output
    report = json.loads(result.stdout)
    assert report["run_dir"] == str(run_dir) and list(report["missions"]) == ["cross"]
    metrics = json.loads(_invoke(["metrics", str(run_dir), "--mission", "cross", "--json"]).stdout)["metrics"]
    assert flatten(report["missions"]["cross"]["social"]) == flatten(metrics)
    baseline = report["missions"]["cross"]["baseline"]
    assert baseline["dynamic"] is None and baseline["distance_travelled_m"] > 0
    # the same by id and by mission; nothing re-run: the run directory holds one run still
    by_id = json.loads(_invoke(["report", run_dir.name, "--mission", "cross", "--json"],
                               CHRONAV_RUNS=str(run_dir.parent)).stdout)
    assert by_id["missions"] == report["missions"]
    assert len([p for p in run_dir.parent.iterdir() if p.is_dir()]) == 1


def test_a_run_from_before_the_slices_gets_them_when_reported(run_dir: Path, tmp_path: Path) -> None:
    old = tmp_path / "old-run"
    shutil.copytree(run_dir, old, ignore=shutil.ignore_patterns("missions"))
    result = _invoke(["report", str(old), "--json"])
    assert result.exit_code == 0, result.output
    assert (old / "missions" / "cross.people.csv").read_bytes() == (run_dir / "missions" / "cross.people.csv").read_bytes()


def _check_plain_80(text: str) -> None:
    """Piped at 80 columns: no line longer, every metric's name whole on one line, each note once."""
    lines = text.splitlines()
    assert lines and max(len(line) for line in lines) <= 80, max(lines, key=len)
    for key in ("distance_travelled_m", "dynamic.avg_distance_to_closest_person_m",
                "dynamic.group_personal_intrusions_percent", "dynamic.robot_intimate_entries"):
        label = column_label(key)
        assert any(label in line for line in lines), label
    assert "- (" not in text, "a missing value's reason is a footnote, not a cell"
    words = " ".join(text.split())
    assert text.count("[1] baseline:") == 1 and "planned at the mission's start, not driven" in words
    assert "its tau is its length over that speed" in words
    assert text.count("- [1]") >= 20    # every metric among moving people of the baseline points to it
    assert "\u2502" not in text and "\u2501" not in text   # a plain layout: no box drawing in a log


def test_report_piped_at_80_columns_keeps_whole_names_and_one_footnote(run_dir: Path) -> None:
    result = _invoke(["report", str(run_dir)], COLUMNS="80")
    assert result.exit_code == 0, result.output
    _check_plain_80(result.stdout)


def test_the_demos_tables_are_the_reports_piped(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                monkeypatch: pytest.MonkeyPatch) -> None:
    """The demo prints its tables with the report's code: run the demo's path (in process), piped."""
    from tools.system.console import run_with_progress

    monkeypatch.setenv("COLUMNS", "80")
    monkeypatch.setenv("CHRONAV_RUNS", str(tmp_path))
    code = run_with_progress(str(WALKERS), rate=None, timeout_s=120, record=False, restart_limit=0, as_json=False,
                             with_report=True, in_process=True)
    assert code == 0
    out = capsys.readouterr().out
    # the metrics, then the run's summary (the missions table, where the run is: not this test's)
    _check_plain_80(out[out.index("eval_walkers / cross: social planner"):out.index("Missions of eval_walkers")])


@pytest.mark.slow   # a sweep's worker process (~8 s)
def test_a_study_carries_every_metric_chronav_metrics_computes_among_walking_people(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Fails when a metric of `chronav metrics` (people given) is missing from a study's table, its
    summary, its paired tests or its report: the study is `chronav evaluate` on eval_walkers."""
    import math

    import tools.evaluate.figures
    from agents.lib.metrics.metric_catalog import CATALOG
    from tools.evaluate.figures import study_metrics
    from tools.evaluate.table import META_COLUMNS, headline_metric, read_table

    drawn: list[list[str]] = []
    monkeypatch.setattr(tools.evaluate.figures, "all_figures",     # the box plots: one per study metric
                        lambda rows, *a, **k: drawn.append(study_metrics(rows)) or {})
    out = tmp_path / "study"
    result = _invoke(["evaluate", str(WALKERS), "--planners", "social,baseline", "--seeds", "1", "--jobs", "1",
                      "--no-record", "--out", str(out), "--json"], RERUN="off")
    assert result.exit_code == 0, result.output
    rows = read_table(out / "table.parquet")
    assert sorted(r["planner"] for r in rows) == ["baseline", "social"]
    for row in rows:
        measured = {k: v for k, v in row.items() if k not in META_COLUMNS}
        by_hand = _invoke(["metrics", str(WALKERS), row["trajectory_csv"], "--json"])
        assert by_hand.exit_code == 0, by_hand.output
        report = json.loads(by_hand.stdout)
        assert report["people"] is not None
        expected = flatten(report["metrics"])
        assert set(expected) - set(measured) == set(), "metrics of chronav metrics missing from the study"
        assert measured == expected
    dynamic = [m.key for m in CATALOG if m.key.startswith("dynamic.") and not m.key.endswith(".*")]
    assert len(dynamic) >= 25
    for key in dynamic:
        assert all(math.isfinite(r[key]) for r in rows), key
    assert set(dynamic) <= set(drawn[0])
    summary = (out / "summary.csv").read_text()
    tests = (out / "tests.csv").read_text()
    html = (out / "report.html").read_text()
    head = html[html.index("<h2>Summary</h2>"):html.index("<h2>Per mission")]
    for key in dynamic:
        assert f",{key}," in summary and f"{key}," in tests, key
        assert headline_metric(key) and f'title="{key}"' in head, key
    assert "dynamic.intrusions_per_person.visitor.intimate" in summary
    assert not headline_metric("dynamic.intrusions_per_person.visitor.intimate")


def test_any_mission_id_gets_its_own_slices_inside_the_runs_missions_folder(run_dir: Path, tmp_path: Path) -> None:
    """Mission ids are any printable names: one with a path in it, or ending like a people slice."""
    from tools.system.mission_slices import read_mission_slices, write_mission_slices

    other = tmp_path / "run"
    other.mkdir()
    for name in ("trajectory.csv", "people.csv"):
        shutil.copy(run_dir / name, other / name)
    cross = json.loads((run_dir / "result.json").read_text())["missions"]["cross"]
    missions = {name: {**cross, "mission_id": name} for name in ("../../escape", "cross", "cross.people", "a b")}
    written = write_mission_slices(other, missions)
    assert sorted(written) == sorted(missions)
    files = sorted(p.name for p in (other / "missions").iterdir())
    assert len(files) == 12 and not (tmp_path / "escape.csv").exists()
    assert (other / "missions" / "cross.people.csv").read_text().startswith("t,name,role")
    assert read_mission_slices(other).keys() == written.keys()
    result = _invoke(["metrics", str(WALKERS), str(written["../../escape"].trajectory_csv), "--json"])
    assert result.exit_code == 0 and json.loads(result.stdout)["people"] == str(written["../../escape"].people_csv)
