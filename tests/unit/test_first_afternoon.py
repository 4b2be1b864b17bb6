"""The small things a newcomer trips on (issue 39, point 5): one regression test each, through the
`chronav` CLI as a user types it."""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

from typer.testing import CliRunner

from tests.integration.test_export_mcap import _run_dir
from tests.support import REPO_ROOT
from tools.cli import app

runner = CliRunner()


def test_export_latest_is_the_newest_finished_run(tmp_path: Path) -> None:
    runs = tmp_path / "recordings"
    runs.mkdir()
    older = _run_dir(runs)
    newer = older.rename(runs / "newer-run")
    _run_dir(runs)                                   # an older finished run beside it
    now = time.time()
    os.utime(runs / "ros_lounge-run" / "result.json", (now - 100, now - 100))
    (runs / "live-run").mkdir()                      # newest, but not finished: no result.json
    out = tmp_path / "latest.mcap"
    result = runner.invoke(app, ["export", "latest", "--out", str(out), "--json"], env={"CHRONAV_RUNS": str(runs)})
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["run_dir"] == str(newer.absolute())
    assert out.exists()
    empty = tmp_path / "empty"
    empty.mkdir()
    refused = runner.invoke(app, ["export", "latest", "--out", str(out)], env={"CHRONAV_RUNS": str(empty)})
    assert refused.exit_code == 1 and f"no finished run of yours under {empty}" in refused.stderr
    assert "Traceback" not in refused.output


SCENE_DIR = REPO_ROOT / "scenes"
