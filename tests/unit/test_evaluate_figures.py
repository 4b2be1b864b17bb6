"""The evaluate report's figures and layout (issue 33): no figure twice, strip plots below five
seeds, axes with units, run metadata shown but never tested.  Rows are written here; the figures
and the report are the real code (matplotlib, Agg)."""

from __future__ import annotations

import base64
import csv
from pathlib import Path

import numpy as np
import pytest

from tools.evaluate import figures as evaluate_figures
from tools.evaluate.figures import METADATA_COLUMNS, box_plot, clock_ticks, metric_label, study_metrics
from tools.evaluate.report import write_report


def _rows(seeds: int) -> list[dict]:
    rows = []
    for planner, offset in (("social", 0.0), ("baseline", -1.0)):
        for seed in range(1, seeds + 1):
            rows.append({"scene": "s", "mission": "m", "planner": planner, "seed": seed, "state": "done",
                         "mission_time_s": 36000.0, "distance_travelled_m": 10.0 + offset + 0.1 * seed,
                         "samples": 100.0 + seed})
    return rows


def _count_boxplots(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    import matplotlib.axes

    calls: list[int] = []
    real = matplotlib.axes.Axes.boxplot

    def spy(self, data, *args, **kwargs):
        calls.append(len(data))
        return real(self, data, *args, **kwargs)

    monkeypatch.setattr(matplotlib.axes.Axes, "boxplot", spy)
    return calls


def test_two_seeds_are_a_strip_plot_and_five_a_box_plot(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    calls = _count_boxplots(monkeypatch)
    assert box_plot(_rows(2), "distance_travelled_m", ["social", "baseline"], tmp_path / "two.png") is not None
    assert calls == [], "a box over two seeds draws quartiles that do not exist"
    assert box_plot(_rows(5), "distance_travelled_m", ["social", "baseline"], tmp_path / "five.png") is not None
    assert calls == [2], "from five seeds each planner gets its box"


def test_metadata_is_neither_plotted_nor_tested_but_shown(tmp_path: Path) -> None:
    rows = _rows(6)
    assert "samples" in METADATA_COLUMNS and study_metrics(rows) == ["distance_travelled_m"]
    figures = evaluate_figures.all_figures(rows, {}, tmp_path, ["social", "baseline"])
    assert [p.name for p in figures["boxes"]] == ["box_distance_travelled_m.png"]
    prov = {"chronav": "test", "created": "now", "command": "chronav evaluate", "executor": "local", "jobs": 1,
            "planners": ["social", "baseline"], "seeds": list(range(1, 7)), "scenes": {}}
    report = write_report(tmp_path, rows, [], prov, figures, ["social", "baseline"]).read_text()
    with (tmp_path / "tests.csv").open() as handle:
        tested = {row["metric"] for row in csv.DictReader(handle)}
    assert tested == {"distance_travelled_m"}, "a sample count is no finding"
    assert "run metadata (not a metric, not tested)" in report
    assert metric_label("samples") in report


def test_the_main_figure_is_shown_once(tmp_path: Path) -> None:
    rows = _rows(2) + [{**r, "mission": "other", "distance_travelled_m": 5.0} for r in _rows(2)]
    paths = []
    for mission, colour in (("m", 0), ("other", 255)):
        path = tmp_path / f"paths_s_{mission}.png"
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        plt.imsave(path, np.full((4, 4, 3), colour, dtype=np.uint8))
        paths.append(path)
    prov = {"chronav": "test", "created": "now", "command": "c", "executor": "local", "jobs": 1,
            "planners": ["social", "baseline"], "seeds": [1, 2], "scenes": {}}
    report = write_report(tmp_path, rows, [], prov, {"paths": paths}, ["social", "baseline"]).read_text()
    for path in paths:
        assert report.count(base64.b64encode(path.read_bytes()).decode("ascii")) == 1, path.name


def test_clock_ticks_give_a_short_day_enough_labels() -> None:
    ticks = clock_ticks(9 * 3600.0, 10.5 * 3600.0)   # eval_tiny's day: whole hours gave two labels
    assert len(ticks) >= 5 and np.all(np.diff(ticks) == ticks[1] - ticks[0])
    assert clock_ticks(9 * 3600.0, 18 * 3600.0)[1] - clock_ticks(9 * 3600.0, 18 * 3600.0)[0] == 3600.0
