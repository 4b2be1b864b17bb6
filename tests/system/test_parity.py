"""Issue 30 acceptance: `chronav evaluate --mode in-process` computes the runs a full launch computes.

Both modes run a walking-crowd scene (tests/data/crowd_eval.yaml: eight people walking their day,
two missions; social planner) with one seed, through the command line a user types.  Every metric of
every mission must be identical (no tolerance: the modes step the same agents through the same
ticks, so they must give the same floats), and so must the run's outputs the metrics come from
(trajectory.csv, people.csv).  The launch runs while the in-process run takes the other core, so
its agents interleave as load decides.
(That repeat in-process runs of one seed are identical: tests/unit/test_lockstep.py; a second
in-process sweep here cost ~40 s of the suite's 2 cores and showed nothing more.  The same parity on
the tiny scene, social and baseline planners, launch against an in-process run on a Dask worker:
tests/system/test_evaluate.py, whose sweeps already ran both; here they cost two more launches and
two more in-process runs, ~2 of the suite's minutes on the 2-core machine, for the same check.)
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import pytest

from tests.support import REPO_ROOT
from tests.system.launch_helpers import EvaluateRuns, Sweep
from tools.evaluate.table import read_table

pytestmark = pytest.mark.slow

CROWD = REPO_ROOT / "tests" / "data" / "crowd_eval.yaml"
#: (scene, planners) of each sweep: on the crowd scene the social planner only (a launch of it takes
#: ~2 wall minutes on the loaded 2-core machine; the baseline's, which waits behind people, ~5)
STUDIES = {"crowd": (CROWD, "social")}
#: columns that say where and how fast a run ran, not what it computed
WHERE = {"run_dir", "rrd", "host", "run_wall_s", "trajectory_csv"}


def _merged(results: list[dict[str, Any]]) -> dict[str, Any]:
    return {"returncode": max(r["returncode"] for r in results), "runs": sum(r["runs"] for r in results),
            "figures": {kind: [p for r in results for p in r["figures"][kind]] for kind in results[0]["figures"]},
            "ok": sum(r["ok"] for r in results), "pending": sum(r["pending"] for r in results),
            "modes": {r["mode"] for r in results}, "tables": [r["table"]["parquet"] for r in results]}


@pytest.fixture(scope="module")
def sweeps(tmp_path_factory: pytest.TempPathFactory, evaluate_runs: EvaluateRuns) -> dict[str, dict[str, Any]]:
    """The launch sweep and, meanwhile, the same sweep in-process."""
    base = tmp_path_factory.mktemp("parity")

    def sweep(out: Path, scene: Path, planners: str, mode: str) -> Sweep:
        # --no-figures: the runs are compared, not the report; drawing its 85 figures was the last
        # ~12 CPU seconds of each sweep (the report's figures: tests/system/test_evaluate.py)
        return evaluate_runs.start(scene, out, planners, "--first-seed", "4", "--jobs", "1", "--mode", mode,
                                   "--no-figures", run_timeout_s=600)

    launches = {name: sweep(base / f"launch_{name}", scene, planners, "launch")
                for name, (scene, planners) in STUDIES.items()}
    found = {}
    for run in ("in_process",):
        found[run] = _merged([evaluate_runs.result(sweep(base / f"{run}_{name}", scene, planners, "in-process"),
                                                   timeout_s=1200) for name, (scene, planners) in STUDIES.items()])
    found["launch"] = _merged([evaluate_runs.result(proc, timeout_s=1200) for proc in launches.values()])
    return found


def _rows(sweep: dict[str, Any]) -> dict[tuple[str, str, int, str], dict[str, Any]]:
    return {(r["scene"], r["planner"], r["seed"], r["mission"]): r
            for table in sweep["tables"] for r in read_table(Path(table))}


def _same(a: Any, b: Any) -> bool:
    return a == b or (isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b))


def test_every_run_completes_in_both_modes(sweeps: dict[str, dict[str, Any]]) -> None:
    for name, sweep in sweeps.items():
        assert sweep["returncode"] == 0, (name, sweep)
        assert (sweep["runs"], sweep["ok"], sweep["pending"]) == (1, 1, 0), (name, sweep)
        assert sweep["modes"] == {"launch" if name == "launch" else "in-process"}
    missions = {key[3] for key in _rows(sweeps["launch"])}
    assert missions == {"to_lounge", "to_therapy"}
    for sweep in sweeps.values():
        assert sweep["figures"] == {"paths": [], "r_of_t": [], "boxes": []}


def test_every_metric_of_every_mission_is_identical(sweeps: dict[str, dict[str, Any]]) -> None:
    reference, compared = _rows(sweeps["launch"]), _rows(sweeps["in_process"])
    assert reference.keys() == compared.keys()
    for key, row in reference.items():
        assert row["state"] == "done", (key, row)
        columns = set(row) - WHERE
        assert columns == set(compared[key]) - WHERE
        different = {c: (row[c], compared[key][c]) for c in sorted(columns) if not _same(row[c], compared[key][c])}
        assert not different, (key, different)
        assert len(columns) > 15, "the table holds the metrics"


@pytest.mark.parametrize("output", ["trajectory.csv", "people.csv"])
def test_the_runs_outputs_are_byte_identical(sweeps: dict[str, dict[str, Any]], output: str) -> None:
    reference, compared = _rows(sweeps["launch"]), _rows(sweeps["in_process"])
    for key, row in reference.items():
        mine, theirs = Path(row["run_dir"]) / output, Path(compared[key]["run_dir"]) / output
        assert mine.read_bytes() == theirs.read_bytes(), (key, output)
        header, *lines = mine.read_text().splitlines()
        assert len(lines) > 100
        if output == "people.csv":   # people walk while the robot drives: a real test of perception
            moving = [ln for ln in lines if abs(float(ln.split(",")[6])) + abs(float(ln.split(",")[7])) > 0.1]
            assert len(moving) > 100, "people walk during the missions"
