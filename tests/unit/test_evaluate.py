"""`chronav evaluate` without launching anything: the table, the statistics, resume and bad input.

The runs are replaced by a stand-in for tools.launch.run_system that drives the robot straight
across the tiny scene; everything after it (per-mission CSVs, `chronav metrics`'s library
function, the ledger, the report) is the real code.  tests/system/test_evaluate.py launches for real.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from agents.lib.metrics.metrics import flatten
from tests.support import REPO_ROOT
from tools.cli import app
from tools.evaluate import sweep as evaluate_sweep
from tools.evaluate.command import evaluate
from tools.evaluate.stats import paired_tests, summarise
from tools.evaluate.table import read_table

TINY = REPO_ROOT / "tests" / "data" / "eval_tiny.yaml"


def test_flatten_metrics_takes_every_number_and_names_nested_ones() -> None:
    # the study's columns: every number of a metrics report, nested names joined with a dot
    flat = flatten({"d_t": 2, "d_min_person_m": {"ann": 1.5}, "psi": {"zone": {"intimate": 0.0}},
                   "psi_basis": "path_length", "moved": True})
    assert flat == {"d_t": 2.0, "d_min_person_m.ann": 1.5, "psi.zone.intimate": 0.0, "moved": 1.0}


def _rows(planner: str, values: list[float]) -> list[dict]:
    return [{"scene": "s", "mission": "m", "planner": planner, "seed": seed, "state": "done", "mission_time_s": 0.0,
             "d_t": value} for seed, value in enumerate(values, start=1)]


def test_mean_std_and_paired_wilcoxon_against_hand_values() -> None:
    social = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]
    rows = _rows("social", social) + _rows("baseline", [v + 0.1 * k for k, v in enumerate(social, start=1)])
    cell = next(s for s in summarise(rows) if s.planner == "social")
    assert (cell.n, cell.mean, cell.std) == (6, 3.5, pytest.approx(math.sqrt(3.5)))
    (test,) = paired_tests(rows)
    # Six pairs, every difference negative: W = 0, exact two-sided p = 2 / 2**6.
    assert (test.other, test.pairs, test.nonzero, test.statistic) == ("baseline", 6, 6, 0.0)
    assert test.p_value == pytest.approx(2 / 64)
    assert test.median_difference == pytest.approx(-0.35)
    tied = paired_tests(_rows("social", [1.0, 2.0]) + _rows("baseline", [1.0, 2.0]))
    assert tied[0].nonzero == 0 and math.isnan(tied[0].p_value)


class FakeLaunch:
    """Stands in for tools.launch.run_system: the robot drives straight across the tiny scene."""

    def __init__(self, interrupt_planner: str | None = None) -> None:
        self.calls: list[dict[str, list[str]]] = []
        self.interrupt_planner = interrupt_planner

    def __call__(self, scene, *, runs_dir, agent_options, **_kwargs):
        from tools.launch import RunResult

        self.calls.append(agent_options)
        planner = next(o.split("=", 1)[1] for o in agent_options["social_navigation"] if o.startswith("planner="))
        if planner == self.interrupt_planner:
            raise KeyboardInterrupt
        run_dir = Path(runs_dir) / f"fake-{planner}-{len(self.calls)}"
        run_dir.mkdir(parents=True)
        t = 36000.0 + np.arange(0, 11.01, 0.1)
        y = 1.2 + (0.0 if planner == "baseline" else 1.2) * np.sin(np.pi * (t - 36000.0) / 11.0)
        x = np.linspace(0.8, 5.2, len(t))
        rows = "".join(f"{a:.3f},{b:.4f},{c:.4f},0.0\n" for a, b, c in zip(t, x, y, strict=True))
        (run_dir / "trajectory.csv").write_text("t,x,y,theta\n" + rows)
        missions = {"cross": {"time_s": 36000.0, "state": "done", "started_s": 36000.0, "finished_s": 36011.0}}
        return RunResult(scene="eval_tiny", run_dir=run_dir, rrd_path=None, missions=missions, events=[],
                         restarts={}, wall_s=1.0)


@pytest.fixture()
def in_thread(monkeypatch: pytest.MonkeyPatch) -> None:
    """Each run in the calling thread instead of its own process (the stand-in lives here)."""
    monkeypatch.setattr(evaluate_sweep, "run_isolated", lambda spec, runs_dir, timeout_s, live=None, record=True:
                        evaluate_sweep.execute_run(evaluate_sweep.RunSpec.from_dict(spec), Path(runs_dir), timeout_s))


def _evaluate(out: Path, resume: bool) -> dict:
    return evaluate([str(TINY)], planners="social,baseline", seeds=1, first_seed=4, jobs=1, out=out,
                    executor_text="local", resume=resume, timeout_s=60.0, quiet=True, command="test", mode="launch")


def test_an_interrupted_sweep_resumes_where_it_stopped(tmp_path: Path, in_thread: None,
                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    import tools.evaluate.figures

    first = FakeLaunch(interrupt_planner="baseline")
    monkeypatch.setattr("tools.launch.run_system", first)
    monkeypatch.setattr(tools.evaluate.figures, "all_figures", lambda *a, **k: {})   # the system test draws them
    stopped = _evaluate(tmp_path, resume=False)
    assert stopped["interrupted"] and stopped["pending"] == 1 and stopped["launched"] == 1
    assert first.calls[0]["social_navigation"] == ["seed=4", "perception_lockstep=1", "planner=social",
                                                   "controller=elastic_band"]
    assert first.calls[0]["human_observer"] == ["seed=4", "perception_lockstep=1"]
    assert {"busy_rate=0", "perception_lockstep=1"} <= set(first.calls[0]["sim_robot"])

    second = FakeLaunch()
    monkeypatch.setattr("tools.launch.run_system", second)
    resumed = _evaluate(tmp_path, resume=True)
    assert [c["social_navigation"][-2] for c in second.calls] == ["planner=baseline"]   # only what was missing
    assert (resumed["launched"], resumed["resumed"], resumed["pending"], resumed["interrupted"]) == (1, 1, 0, False)
    rows = read_table(Path(resumed["table"]["parquet"]))
    assert sorted(r["planner"] for r in rows) == ["baseline", "social"]
    straight = next(r for r in rows if r["planner"] == "baseline")
    assert straight["distance_travelled_m"] == pytest.approx(4.4) and straight["seed"] == 4
    report = Path(resumed["report"]).read_text()
    # The summary first, one table whatever the seeds; the per-mission tables and the runs folded.
    assert report.index("<h2>Summary</h2>") < report.index("<details><summary><b>eval_tiny / cross</b>")
    assert "<td>missions completed (runs x missions)</td><td>1 / 1</td><td>1 / 1</td>" in report
    summary = report[report.index("<h2>Summary</h2>"):report.index("<h2>Per mission")]
    assert "4.4" in summary and "<details>" not in summary and "full launch of the six agents" in report
    assert "<summary>2 runs (click to show)</summary>" in report


def test_no_figures_writes_the_report_without_drawing_any(tmp_path: Path, in_thread: None,
                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    """`--no-figures` (a sweep whose table is what counts: tests/system/test_parity.py): no PNG is
    drawn, the report says so, and its tables are all there."""
    monkeypatch.setattr("tools.launch.run_system", FakeLaunch())
    result = CliRunner().invoke(app, ["evaluate", str(TINY), "--planners", "social,baseline", "--seeds", "1",
                                      "--jobs", "1", "--mode", "launch", "--no-figures", "--out", str(tmp_path),
                                      "--json"])
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout)
    assert summary["figures"] == {"paths": [], "r_of_t": [], "boxes": []}
    assert not list(tmp_path.glob("*.png"))
    report = Path(summary["report"]).read_text()
    assert "Not drawn: the study ran with <code>--no-figures</code>" in report and "<img" not in report
    assert "<h2>Summary</h2>" in report and "<summary>2 runs (click to show)</summary>" in report
    assert json.loads((tmp_path / "sweep.json").read_text())["figures"] is False


@pytest.mark.parametrize(("args", "words"), [
    (["--planners", "social,nav2"], "unknown planner 'nav2'"),
    (["--planners", "social,social"], "named twice"),
    (["--resume"], "--resume continues the sweep in --out DIR"),
    (["--executor", "ray://host:1"], "use local or dask://HOST:PORT"),
    (["--executor", "dask://nohost"], "expected dask://HOST:PORT"),
    (["--seeds", "0"], "--seeds: give at least 1"),
    (["--mode", "threads"], "--mode threads: use one of in-process, launch"),
])
def test_bad_input_is_one_line_and_launches_nothing(args: list[str], words: str, tmp_path: Path) -> None:
    extra = [] if "--resume" in args else ["--out", str(tmp_path / "study")]
    result = CliRunner().invoke(app, ["evaluate", str(TINY), *args, *extra])
    assert result.exit_code == 2, result.output
    assert words in " ".join(result.output.split())
    assert not (tmp_path / "study" / "runs").exists()


def test_a_finished_sweep_is_not_overwritten(tmp_path: Path) -> None:
    (tmp_path / "runs.jsonl").write_text(json.dumps({"key": "x"}) + "\n")
    result = CliRunner().invoke(app, ["evaluate", str(TINY), "--out", str(tmp_path)])
    assert result.exit_code == 2 and "continue it with --resume" in " ".join(result.output.split())


def test_progress_gives_each_planner_its_own_eta(monkeypatch: pytest.MonkeyPatch) -> None:
    """A planner whose runs take twice as long has twice the time left per run left."""
    from tools.evaluate import command as evaluate_module
    from tools.evaluate.sweep import RunSpec, plan_sweep

    clock = [100.0]
    monkeypatch.setattr(evaluate_module.time, "monotonic", lambda: clock[0])
    specs = plan_sweep([TINY], ["social", "baseline"], [1, 2, 3])
    progress = evaluate_module._Progress(specs, quiet=True)
    for spec, wall in ((RunSpec(str(TINY), "social", 1), 2.0), (RunSpec(str(TINY), "baseline", 1), 1.0)):
        clock[0] += wall
        progress.advance({"spec": spec.to_dict(), "outcome": "ok", "wall_s": wall})
    # 3 wall s for 2 runs: 1.5 s a run on average; social's runs cost 2/1.5 of that, baseline's 1/1.5.
    assert progress.eta_s() == pytest.approx(1.5 * 4)
    assert progress.eta_s("social") == pytest.approx(1.5 * (2.0 / 1.5) * 2)
    assert progress.eta_s("baseline") == pytest.approx(1.5 * (1.0 / 1.5) * 2)
