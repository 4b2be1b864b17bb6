"""A controller plug-in that answers NaN, through `chronav launch --in-process --controller`: the
navigation logs it, stops the robot, fails that mission naming the plug-in and its package, and
nothing crashes (the run ends normally with exit code 1, a mission not done)."""

from __future__ import annotations

import json

from tests.plugin_fixtures import install_fake_plugins
from tests.support import REPO_ROOT, ProcessGroup

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
