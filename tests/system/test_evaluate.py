"""Issue 16 and 30 acceptance on the tiny scene: `chronav evaluate --mode launch` launches real runs
(two planners, one seed) on this machine and the same pair runs in-process on a Dask LocalCluster of
2 workers; the report's tables are `chronav metrics` on the runs' trajectories, and the two runs of
one seed give identical metrics from byte-identical trajectories.  A second cluster loses a worker in the middle of a run: the run is
queued again once and the sweep completes.

Two launches and two in-process runs (both sweeps at once), shared by every test of the module.
"""

from __future__ import annotations

import base64
import csv
import hashlib
import json
import math
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

from agents.lib.metrics.metrics import flatten, read_trajectory_csv
from tests.support import REPO_ROOT
from tests.system.launch_helpers import EvaluateRuns
from scenes.clock import format_clock
from tools.cli import app
from tools.evaluate.report import format_value
from tools.evaluate.table import META_COLUMNS, read_table

pytestmark = pytest.mark.slow

TINY = REPO_ROOT / "tests" / "data" / "eval_tiny.yaml"
PLANNERS = "social,baseline"
RERUN_ON = {"RERUN": "on"}    # the report links each run's recording


@pytest.fixture(scope="module")
def sweeps(tmp_path_factory: pytest.TempPathFactory, evaluate_runs: EvaluateRuns) -> dict[str, dict[str, Any]]:
    """Both sweeps at once (4 launches, 2 by 2): the same pair here and on the cluster."""
    from distributed import LocalCluster

    base = tmp_path_factory.mktemp("evaluate")
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster:
        local = evaluate_runs.start(TINY, base / "local", PLANNERS, "--jobs", "2", "--mode", "launch", env=RERUN_ON)
        # the report is checked on the local sweep; the dask sweep's runs are compared with it, so its
        # figures (one per metric, ~0.1 s of CPU each) would only slow the local one down
        dask = evaluate_runs.start(TINY, base / "dask", PLANNERS, "--executor",
                                   f"dask://{cluster.scheduler_address.removeprefix('tcp://')}", "--mode", "in-process",
                                   "--no-figures", env=RERUN_ON)
        return {"local": evaluate_runs.result(local), "dask": evaluate_runs.result(dask)}


def _key(row: dict[str, Any]) -> tuple:
    return row["scene"], row["planner"], row["seed"], row["mission"]


def test_both_executors_run_every_combination(sweeps: dict[str, dict[str, Any]]) -> None:
    for name, sweep in sweeps.items():
        assert sweep["returncode"] == 0, (name, sweep)
        assert (sweep["runs"], sweep["launched"], sweep["ok"], sweep["pending"]) == (2, 2, 2, 0), sweep
        rows = read_table(Path(sweep["table"]["parquet"]))
        assert sorted(r["planner"] for r in rows) == ["baseline", "social"]
        for row in rows:
            assert row["state"] == "done" and Path(row["rrd"]).stat().st_size > 0, row
            assert json.loads((Path(row["run_dir"]) / "evaluate.json").read_text())["planner"] == row["planner"]
        with open(sweep["table"]["csv"], newline="") as handle:
            assert len(list(csv.DictReader(handle))) == len(rows)


def test_table_and_report_are_chronav_metrics_of_the_runs(sweeps: dict[str, dict[str, Any]], tmp_path: Path) -> None:
    sweep = sweeps["local"]
    rows = read_table(Path(sweep["table"]["parquet"]))
    with open(Path(sweep["out"]) / "summary.csv", newline="") as summary_file:
        summary = {(r["planner"], r["metric"]): float(r["mean"]) for r in csv.DictReader(summary_file)}
    report = Path(sweep["report"]).read_text()
    for row in rows:
        # Cut the mission out of the run's trajectory and people ourselves, from the launcher's result.json,
        # and measure it as a user would: the people, the mission's start and its target given by hand.
        mission = json.loads((Path(row["run_dir"]) / "result.json").read_text())["missions"][row["mission"]]
        started, finished = mission["started_s"], mission["finished_s"]
        trajectory = read_trajectory_csv(Path(row["run_dir"]) / "trajectory.csv")
        inside = (trajectory[:, 0] >= started - 1e-6) & (trajectory[:, 0] <= finished + 1e-6)
        own = tmp_path / f"{row['planner']}.csv"
        np.savetxt(own, trajectory[inside], delimiter=",", header="t,x,y,theta", comments="", fmt="%.17g")
        header, *lines = (Path(row["run_dir"]) / "people.csv").read_text().splitlines()
        own_people = tmp_path / f"{row['planner']}_people.csv"
        own_people.write_text("\n".join([header, *(line for line in lines
                                                  if started - 1e-6 <= float(line.split(",")[0]) <= finished + 1e-6)]))
        assert started == int(started), "the mission starts on a whole second: --at can say when"
        goal = ",".join(mission["goal"].removeprefix("pose:").split(",")[:2])
        result = CliRunner().invoke(app, ["metrics", str(TINY), str(own), "--people", str(own_people), "--goal", goal,
                                          "--at", format_clock(started), "--json"])
        assert result.exit_code == 0, result.output
        expected = flatten(json.loads(result.stdout)["metrics"])
        assert any(key.startswith("dynamic.") for key in expected), "measured among the moving people"
        # The run's own slice, measured by `chronav metrics` with nothing else said, gives the same.
        beside = CliRunner().invoke(app, ["metrics", str(TINY), row["trajectory_csv"], "--json"])
        assert beside.exit_code == 0, beside.output
        assert flatten(json.loads(beside.stdout)["metrics"]) == expected
        measured = {k: v for k, v in row.items() if k not in META_COLUMNS}
        assert set(measured) == set(expected)
        for metric, value in expected.items():
            assert measured[metric] == pytest.approx(value, rel=1e-9, abs=1e-12), metric
            assert summary[(row["planner"], metric)] == pytest.approx(value, rel=1e-9, abs=1e-12), metric
            assert f"<td>{format_value(value)} (n=1)</td>" in report, (row["planner"], metric)


def test_two_runs_with_one_seed_are_identical(sweeps: dict[str, dict[str, Any]]) -> None:
    """A launch here and an in-process run on a Dask worker: the same numbers, to the last bit, from
    the same outputs, byte for byte (the parity of the two modes on this scene; on walking people:
    tests/system/test_parity.py)."""
    local = {_key(r): r for r in read_table(Path(sweeps["local"]["table"]["parquet"]))}
    remote = {_key(r): r for r in read_table(Path(sweeps["dask"]["table"]["parquet"]))}
    assert local.keys() == remote.keys()
    for key, row in local.items():
        other = remote[key]
        assert row["run_dir"] != other["run_dir"]
        for metric, value in row.items():
            if metric in META_COLUMNS:
                continue
            assert value == other[metric] or (math.isnan(value) and math.isnan(other[metric])), \
                (key, metric, value, other[metric])
        for output in ("trajectory.csv", "people.csv"):
            mine, theirs = Path(row["run_dir"]) / output, Path(other["run_dir"]) / output
            assert mine.read_bytes() == theirs.read_bytes(), (key, output)


def test_report_is_one_self_contained_file_that_says_what_ran(sweeps: dict[str, dict[str, Any]]) -> None:
    sweep = sweeps["local"]
    out, report = Path(sweep["out"]), Path(sweep["report"]).read_text()
    assert not re.search(r'<img[^>]+src="(?!data:image/png;base64,)', report), "every image is embedded"
    embedded = re.findall(r'src="data:image/png;base64,([^"]+)"', report)
    pngs = sorted(out.glob("*.png"))
    assert {p.name for p in pngs} >= {"paths_eval_tiny_cross.png", "r_of_t_eval_tiny.png",
                                      "box_distance_travelled_m.png"}
    assert {base64.b64decode(e) for e in embedded} >= {p.read_bytes() for p in pngs}
    assert hashlib.sha256(TINY.read_bytes()).hexdigest() in report
    assert "chronav 0." in report and "<td>seeds</td><td>1</td>" in report
    assert "Wilcoxon" in report and ".rrd" in report



def test_a_worker_lost_mid_run_is_queued_again_once(tmp_path: Path, evaluate_runs: EvaluateRuns) -> None:
    """The scheduler is told to give a task up at its worker's first death (allowed-failures 0), so
    what brings the run back is chronav's own re-queue; the worker running the run is SIGKILLed.
    One run (one planner) shows it: a second one only added an in-process run to the suite."""
    import os
    import signal
    import time

    import dask
    from distributed import Client, LocalCluster

    with dask.config.set({"distributed.scheduler.allowed-failures": 0}), \
            LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                         dashboard_address=None) as cluster, Client(cluster) as client:
        sweep = evaluate_runs.start(TINY, tmp_path / "lost", "social", "--executor",
                                    f"dask://{cluster.scheduler_address.removeprefix('tcp://')}", "--mode", "in-process",
                                    "--no-figures", env=RERUN_ON)   # the re-queue is judged, not the report
        victim, deadline = None, time.monotonic() + 180
        while victim is None and time.monotonic() < deadline and sweep.proc.poll() is None:
            busy = [w for w, keys in client.processing().items()
                    if any(str(k).startswith("chronav-evaluate") for k in keys)]
            victim = busy[0] if busy else None
            time.sleep(0.02)
        assert victim is not None, "no run was seen under way on a worker"
        os.kill(client.run(os.getpid, workers=[victim])[victim], signal.SIGKILL)
        result = evaluate_runs.result(sweep)
    assert result["returncode"] == 0, result
    assert (result["runs"], result["ok"], result["pending"]) == (1, 1, 0), result
    assert len(result["requeued"]) == 1, result
    rows = read_table(Path(result["table"]["parquet"]))
    assert [(r["planner"], r["state"]) for r in rows] == [("social", "done")]
