"""The real-time soak's memory slope (tools/soak.py, issue 41): the least-squares fit, the warm-up,
a restarted agent's new series, and sampling a live process; the soak itself is a benchmark
(`tools/bench/bench_week.py --soak-hours H`), its short variant tests/system/test_long_run.py."""

from __future__ import annotations

import os

import pytest

from tools.soak import MemorySeries, fit_slope_per_hour, soak_scene


def test_slope_is_mb_per_hour_and_needs_three_samples_over_time() -> None:
    assert fit_slope_per_hour([(0.0, 100.0), (1800.0, 100.5), (3600.0, 101.0)]) == pytest.approx(1.0)
    noisy = [(60.0 * i, 200.0 + (0.3 if i % 2 else -0.3)) for i in range(60)]
    assert abs(fit_slope_per_hour(noisy) or 0.0) < 0.05      # noise, no climb
    assert fit_slope_per_hour([(0.0, 1.0), (10.0, 2.0)]) is None
    assert fit_slope_per_hour([(5.0, 1.0), (5.0, 2.0), (5.0, 3.0)]) is None


def test_warmup_is_not_fitted_and_a_restart_opens_a_new_series() -> None:
    series = MemorySeries(warmup_s=600.0)
    for minute in range(0, 10):                       # startup: memory climbing fast, not fitted
        series.add("planner", 11, minute * 60.0, 100.0 + 20.0 * minute)
    for minute in range(10, 70):                      # steady: +2 MB over the hour, shared code pages only
        series.add("planner", 11, minute * 60.0, 300.0 + 2.0 * (minute - 10) / 60.0, 120.0)
    for minute in range(70, 75):                      # restarted: memory starts over, which is no fall
        series.add("planner", 12, minute * 60.0, 150.0, 100.0)
    assert series.slopes()["planner"] == pytest.approx(2.0, abs=1e-3)
    assert series.slopes(private=True)["planner"] == pytest.approx(0.0, abs=1e-6)
    report = series.report()
    assert report["soak_mem_slope_mb_per_h_max"] == pytest.approx(2.0, abs=1e-3)
    assert report["soak_agents_over_goal"] == ["planner"] and report["soak_processes_planner"] == 2
    assert report["soak_private_slope_mb_per_h_max"] == pytest.approx(0.0, abs=1e-6)
    assert report["soak_agents_over_goal_private"] == []
    assert report["soak_rss_mb_last_planner"] == 150.0 and report["soak_private_mb_last_planner"] == 100.0
    assert report["soak_samples"] == 65


def test_every_sample_goes_to_the_csv_warmup_included(tmp_path) -> None:
    series = MemorySeries(warmup_s=120.0, samples_csv=tmp_path / "samples.csv")
    for minute in range(4):
        series.add("planner", 11, minute * 60.0, 100.0 + minute)
    series.add("planner", 11, 240.0, 104.0, 61.5)
    lines = (tmp_path / "samples.csv").read_text().splitlines()
    assert lines[0] == "agent,pid,t_s,rss_mb,private_mb" and len(lines) == 6
    assert lines[1] == "planner,11,0.0,100.00," and lines[5] == "planner,11,240.0,104.00,61.50"
    assert len(series.series["planner"][0][1]) == 3          # the fit still skips the warm-up


def test_tick_samples_live_processes_at_its_interval() -> None:
    now = [0.0]
    series = MemorySeries(warmup_s=0.0, sample_every_s=60.0, clock=lambda: now[0])
    for step in range(7):
        now[0] = step * 30.0
        series.tick({"me": os.getpid(), "gone": 2**22 + 7, "unstarted": None})
    samples = series.series["me"][0][1]
    assert [t for t, _, _ in samples] == [0.0, 60.0, 120.0, 180.0] and all(rss > 1.0 for _, rss, _ in samples)
    assert all(private is not None and 0.0 < private < rss for _, rss, private in samples)
    assert "gone" not in series.series and "unstarted" not in series.series


def test_soak_scene_runs_in_real_time_past_the_soak(tmp_path) -> None:
    import yaml

    data = yaml.safe_load(soak_scene("center_day", 1.8, tmp_path / "soak.yaml").read_text())
    assert data["clock"]["rate"] == 1 and data["clock"]["skip_idle"] is False
    assert data["clock"]["start"] == "09:00" and data["clock"]["end"] == "11:18"
