"""A controller plug-in that answers NaN, through `chronav launch --in-process --controller`: the
navigation logs it, stops the robot, fails that mission naming the plug-in and its package, and
nothing crashes (the run ends normally with exit code 1, a mission not done)."""

from __future__ import annotations

import json

import pytest

from tests.plugin_fixtures import install_fake_plugins
from tests.support import REPO_ROOT, ProcessGroup

pytestmark = pytest.mark.slow   # chronav runs in their own processes

TINY = REPO_ROOT / "tests" / "data" / "eval_tiny.yaml"


def test_a_nan_controller_fails_the_mission_naming_it(tmp_path) -> None:
    site = install_fake_plugins(tmp_path / "site")
    log = tmp_path / "launch.log"
    group = ProcessGroup()
    try:
        proc = group.spawn(["-m", "tools.cli", "launch", str(TINY), "--in-process", "--no-record", "--json",
                            "--controller", "nan_ctrl", "--timeout", "120"],
                           env={"PYTHONPATH": f"{site}:{REPO_ROOT}", "CHRONAV_RUNS": str(tmp_path / "runs")},
                           log_path=log)
        proc.wait(timeout=180)
    finally:
        group.close()
    text = log.read_text()
    result = json.loads(next(line for line in reversed(text.splitlines()) if line.startswith("{")))
    assert proc.returncode == 1, text[-2000:]
    assert result["error"] is None and not result["timed_out"]
    mission = result["missions"]["cross"]
    assert mission["state"] == "failed"
    assert ("plug-in refused: controller 'nan_ctrl' from package 'chronav-test-plugins' failed: "
            "returned vx = nan") in mission["reason"]


def test_evaluate_counts_refused_missions_over_planner_x_controller(tmp_path) -> None:
    """`chronav evaluate --planners social,off_map --controllers elastic_band,nan_ctrl`: four runs,
    the three with a broken plug-in fail their mission and are counted; the table has a controller
    column and the report one method per planner x controller."""
    import pyarrow.parquet as pq

    site = install_fake_plugins(tmp_path / "site")
    log = tmp_path / "evaluate.log"
    group = ProcessGroup()
    try:
        proc = group.spawn(["-m", "tools.cli", "evaluate", str(TINY), "--planners", "social,off_map",
                            "--controllers", "elastic_band,nan_ctrl", "--seeds", "1", "--jobs", "1", "--no-record",
                            "--out", str(tmp_path / "study"), "--json"],
                           env={"PYTHONPATH": f"{site}:{REPO_ROOT}", "CHRONAV_RUNS": str(tmp_path / "runs")},
                           log_path=log)
        proc.wait(timeout=300)
    finally:
        group.close()
    text = log.read_text()
    result = json.loads(next(line for line in reversed(text.splitlines()) if line.startswith("{")))
    assert result["runs"] == 4 and result["ok"] == 1 and result["refused_missions"] == 3, text[-2000:]
    rows = pq.read_table(result["table"]["parquet"]).to_pylist()
    by_pair = {(r["planner"], r["controller"]): r for r in rows}
    assert by_pair[("social", "elastic_band")]["state"] == "done"
    assert by_pair[("social", "elastic_band")]["distance_travelled_m"] > 4.0
    assert "controller 'nan_ctrl' from package 'chronav-test-plugins'" in by_pair[("social", "nan_ctrl")]["reason"]
    assert "planner 'off_map'" in by_pair[("off_map", "elastic_band")]["reason"]
    report = (tmp_path / "study" / "report.html").read_text()
    assert "social+nan_ctrl" in report and "off_map+nan_ctrl" in report
