"""examples/plugin, an outside package, installed into a temporary target and used without any
edit to chronav: `chronav plugins` lists its five extensions, `chronav path` plans with its
planner and drives its controller, an in-process `chronav evaluate` runs its planner x controller
(its agent running beside chronav's) and measures its metric, `chronav predict evaluate` scores
its predictor, and `chronav launch`, in-process and as processes, runs its note_taker agent,
whose note nodes are in the run's graph.json.

Why a copy: pip builds in the source folder (build/, *.egg-info); the repository stays clean."""

from __future__ import annotations

import json
import math
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.support import REPO_ROOT

pytestmark = pytest.mark.slow   # processes: pip, chronav runs

TINY = REPO_ROOT / "tests" / "data" / "eval_tiny.yaml"
PACKAGE = "chronav-example-plugin"


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    work = tmp_path_factory.mktemp("plugin")
    source = work / "src"
    shutil.copytree(REPO_ROOT / "examples" / "plugin", source)
    target = work / "site"
    done = subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--target", str(target),
                           str(source)], capture_output=True, text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stderr[-3000:]
    return target


def _chronav(site: Path, *args: str, timeout: float = 300) -> tuple[int, dict]:
    env = {"PATH": "/usr/bin:/bin", "PYTHONPATH": f"{site}:{REPO_ROOT}", "RERUN": "off",
           "CHRONAV_RUNS": str(site.parent / "runs"), "HOME": str(site.parent)}
    done = subprocess.run([sys.executable, "-m", "tools.cli", *args, "--json"], cwd=site.parent, env=env,
                          capture_output=True, text=True, timeout=timeout, check=False)
    lines = [line for line in done.stdout.splitlines() if line.startswith("{")]
    assert lines, f"no JSON from chronav {' '.join(args)}:\n{done.stdout[-2000:]}\n{done.stderr[-3000:]}"
    return done.returncode, json.loads(lines[-1])


def test_plugins_lists_the_packages_extensions(site: Path) -> None:
    code, listed = _chronav(site, "plugins")
    assert code == 0
    ours = {(r["kind"], r["name"]): r for r in listed["plugins"] if r["package"] == PACKAGE}
    assert set(ours) == {("planner", "example_bubble"), ("controller", "example_pursuit"),
                         ("predictor", "example_slowing"), ("metric", "example_efficiency"),
                         ("agent", "note_taker")}
    assert all(r["status"] == "ok" and r["version"] == "0.1.0" for r in ours.values())
    assert ours[("controller", "example_pursuit")]["summary"].startswith("Pure pursuit 0.6 m ahead")
    assert ours[("agent", "note_taker")]["summary"].startswith("Writes a note node each time the robot passes")


@pytest.mark.parametrize("mode", [("--in-process",), ()], ids=["in-process", "processes"])
def test_launch_runs_its_agent_and_its_notes_are_in_the_graph(site: Path, mode: tuple[str, ...]) -> None:
    """The robot crosses the lounge past the resident: the note_taker writes one note about her,
    and the run's graph (the launcher's replica, which took in only what the write policy allowed)
    holds it, with its `about` edge to her person node."""
    code, result = _chronav(site, "launch", str(TINY), *mode, "--no-record", "--timeout", "240")
    assert code == 0 and result["ok"], result
    assert "note_taker" in result["restarts"]                         # it ran as one of the run's agents
    graph = json.loads((Path(result["run_dir"]) / "graph.json").read_text())
    nodes = {n["id"]: n for n in graph["nodes"]}
    notes = [n for n in graph["nodes"] if n["type"] == "note"]
    assert len(notes) == 1, notes
    note = notes[0]["attrs"]
    assert note["person"] == "resident" and note["distance_m"] <= 2.0 and note["text"].startswith("passed resident")
    assert 36000.0 <= note["time_s"] <= 36060.0                       # during the mission (10:00, sim s)
    [about] = [e for e in graph["edges"] if e["type"] == "about"]
    assert nodes[about["src"]]["type"] == "note" and nodes[about["dst"]]["name"] == "resident"


def test_path_plans_with_its_planner_and_drives_its_controller(site: Path) -> None:
    args = ("path", str(TINY), "--at", "10:01", "--from", "0.8,1.2", "--to", "5.2,1.2")
    code, bubble = _chronav(site, *args, "--planner", "example_bubble", "--controller", "example_pursuit")
    _, straight = _chronav(site, *args, "--planner", "baseline")
    assert code == 0 and bubble["planner"] == "example_bubble"
    assert bubble["length_m"] > straight["length_m"]          # the bubble around the resident bends the path
    driven = bubble["controller"]
    assert driven["name"] == "example_pursuit" and driven["reached"] and driven["refused"] is None
    assert math.hypot(driven["points"][-1][0] - 5.2, driven["points"][-1][1] - 1.2) < 0.2


def test_evaluate_runs_its_planner_and_controller_and_measures_its_metric(site: Path) -> None:
    code, study = _chronav(site, "evaluate", str(TINY), "--planners", "example_bubble",
                           "--controllers", "example_pursuit", "--seeds", "1", "--jobs", "1", "--no-record",
                           "--out", str(site.parent / "study"))
    assert code == 0 and study["ok"] == 1 and study["refused_missions"] == 0, study
    import pyarrow.parquet as pq

    [row] = pq.read_table(study["table"]["parquet"]).to_pylist()
    assert (row["planner"], row["controller"], row["state"]) == ("example_bubble", "example_pursuit", "done")
    assert 0.5 < row["example_path_efficiency"] <= 1.0      # the plug-in's column beside chronav's
    assert row["distance_travelled_m"] > 4.0
    assert "example_bubble+example_pursuit" in Path(study["report"]).read_text()


def test_predict_evaluate_scores_its_predictor(site: Path, tmp_path: Path) -> None:
    data = tmp_path / "line.txt"      # one walker slowing down: the damped predictor beats constant velocity
    lines, x = [], 0.0
    for k in range(30):
        x += 0.5 * 0.4 * 0.9 ** k
        lines.append(f"{10 * k}\t1\t{x:.6f}\t0.0")
    data.write_text("\n".join(lines) + "\n", encoding="utf-8")
    code, result = _chronav(site, "predict", "evaluate", str(data), "--predictor", "example_slowing", "--noise", "0")
    assert code == 0
    row = result["files"]["line.txt"]
    assert row["tracks"] > 0 and row["ade"] < row["cv_ade"]
