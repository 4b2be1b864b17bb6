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


def test_scene_from_map_given_a_scene_file_says_so(tmp_path: Path) -> None:
    for scene, hint in ((SCENE_DIR / "center_day.yaml", ""), (SCENE_DIR / "map_ward.yaml", "maps/ward.yaml")):
        result = runner.invoke(app, ["scene", "from-map", str(scene), "--out", str(tmp_path / "x.yaml")])
        assert result.exit_code != 0
        assert "this is a chronav scene file, not a map_server map yaml" in result.stderr, result.stderr
        assert hint in result.stderr and "unknown key" not in result.stderr and "Traceback" not in result.output
        assert not (tmp_path / "x.yaml").exists()


def test_path_outside_the_scenes_day_is_refused_with_its_hours() -> None:
    for at in ("08:00", "18:30"):
        result = runner.invoke(app, ["path", "center_day", "--at", at, "--from", "4,1.2", "--to", "11,4"])
        assert result.exit_code == 2, result.output
        assert (f"--at {at}:00 is outside the day of scene 'center_day', which runs 09:00:00-18:00:00"
                in result.stderr), result.stderr
    plan = runner.invoke(app, ["plan", "center_day", "--mission", "room:lounge", "--at", "08:00"])
    assert plan.exit_code == 2 and "which runs 09:00:00-18:00:00" in plan.stderr


def test_the_license_is_an_spdx_string_so_setuptools_prints_no_deprecation_banner() -> None:
    """A license table made setuptools >= 77 print its deprecation banner on every install."""
    import re
    import tomllib

    project = tomllib.loads((REPO_ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    assert project["project"]["license"] == "Apache-2.0"
    requires = next(r for r in project["build-system"]["requires"] if r.startswith("setuptools"))
    found = re.fullmatch(r"setuptools>=(\d+)(\.\d+)*", requires)
    assert found and int(found[1]) >= 77, requires      # the first setuptools that reads the SPDX string


def test_ros_bridge_with_no_system_says_what_to_do_in_one_line(tmp_path: Path) -> None:
    """Issue 39: `chronav ros bridge SCENE` with no run printed a 40-line traceback."""
    from tests.support import free_port

    endpoint = f"tcp/127.0.0.1:{free_port()}"        # nothing listens there
    result = runner.invoke(app, ["ros", "bridge", "center_day"],
                           env={"CHRONAV_RUNS": str(tmp_path), "CHRONAV_ZENOH_CONNECT": endpoint})
    assert result.exit_code == 2, result.output
    assert "Traceback" not in result.output and len(result.stderr.strip().splitlines()) == 1, result.stderr
    assert result.stderr.startswith(f"chronav ros bridge: cannot reach a chronav system: nothing listens at {endpoint}")
    assert "chronav launch SCENE" in result.stderr
