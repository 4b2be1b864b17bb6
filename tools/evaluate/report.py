"""``DIR/report.html``: one self-contained file (figures embedded as base64 PNG) that says what was
run, with which chronav and which scene files, and what came out.

Also written beside it, for other tools: ``summary.csv`` (mean, std and n per scene, mission,
planner and metric: the numbers in the report's tables) and ``tests.csv`` (the paired tests).
"""

from __future__ import annotations

import base64
import csv
import hashlib
import html
import math
import subprocess
from collections.abc import Mapping, Sequence
from datetime import datetime
from pathlib import Path
from typing import Any

from agents.world.vocabulary import MissionState
from tools.evaluate.prediction_section import live_prediction_html
from tools.evaluate.stats import REFERENCE, PairedTest, Summary, missions_of, paired_tests, planners_of, summarise

REPORT = "report.html"
SUMMARY = "summary.csv"
TESTS = "tests.csv"
SIGNIFICANCE = 0.05


def format_value(value: float) -> str:
    """How a number appears in the report's tables (summary.csv holds it in full)."""
    if value is None or not math.isfinite(value):
        return "-"
    return f"{value:.3f}" if abs(value) < 100 else f"{value:.1f}"


def format_cell(summary: Summary | None) -> str:
    if summary is None:
        return "-"
    if summary.n < 2:
        return f"{format_value(summary.mean)} (n=1)"
    return f"{format_value(summary.mean)} &plusmn; {format_value(summary.std)}"


# ---------------------------------------------------------------------------------------------
# Provenance.
# ---------------------------------------------------------------------------------------------

def sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def chronav_version() -> str:
    """The installed version, plus the git commit of the source tree when there is one."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        text = version("chronav")
    except PackageNotFoundError:
        text = "unknown"
    root = Path(__file__).resolve().parents[2]
    try:
        commit = subprocess.run(["git", "-C", str(root), "rev-parse", "--short", "HEAD"], capture_output=True,
                                text=True, timeout=10, check=False).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(root), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, timeout=10, check=False).stdout.strip()
    except (OSError, subprocess.TimeoutExpired):
        commit = dirty = ""
    return f"{text} (git {commit}{', with local changes' if dirty else ''})" if commit else text


def scene_files(scene: Path) -> list[dict[str, str]]:
    """The scene file and the agenda file it names, each with its SHA-256."""
    from scenes.loader import load_scene

    files = [{"file": str(scene), "sha256": sha256(scene)}]
    agenda_file = load_scene(scene).scene.agenda_file
    if agenda_file:
        agenda = (scene.parent / agenda_file).resolve()
        if agenda.exists():
            files.append({"file": str(agenda), "sha256": sha256(agenda)})
    return files


def provenance(scenes: Sequence[Path], planners: Sequence[str], seeds: Sequence[int], executor: str,
               jobs: int, command: str) -> dict[str, Any]:
    return {"chronav": chronav_version(), "created": datetime.now().astimezone().isoformat(timespec="seconds"),
            "command": command, "executor": executor, "jobs": jobs, "planners": list(planners),
            "seeds": list(seeds), "scenes": {s.stem: scene_files(s) for s in scenes}}


# ---------------------------------------------------------------------------------------------
# Machine-readable numbers.
# ---------------------------------------------------------------------------------------------

def write_summary(summaries: Sequence[Summary], path: Path) -> Path:
    with path.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(["scene", "mission", "planner", "metric", "n", "mean", "std"])
        for s in summaries:
            writer.writerow([s.scene, s.mission, s.planner, s.metric, s.n, repr(s.mean), repr(s.std)])
    return path


def write_tests(tests: Sequence[PairedTest], path: Path) -> Path:
    with path.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(["metric", "planner", "other", "pairs", "nonzero", "median_difference", "statistic",
                         "p_value", "test"])
        for t in tests:
            writer.writerow([t.metric, t.planner, t.other, t.pairs, t.nonzero, repr(t.median_difference),
                             repr(t.statistic), repr(t.p_value), "wilcoxon signed-rank, two-sided, paired by "
                             "(scene, mission, seed)"])
    return path


# ---------------------------------------------------------------------------------------------
# HTML.
# ---------------------------------------------------------------------------------------------

_STYLE = """
body { font-family: system-ui, sans-serif; margin: 2em auto; max-width: 1200px; color: #222; }
h1 { font-size: 1.6em; } h2 { border-bottom: 1px solid #ccc; margin-top: 2em; } h3 { margin-top: 1.5em; }
table { border-collapse: collapse; margin: 0.5em 0 1em; font-size: 0.9em; }
th, td { border: 1px solid #ddd; padding: 3px 8px; text-align: right; }
th:first-child, td:first-child { text-align: left; }
th { background: #f2f2f2; } tr.sig td { background: #eef6ee; }
img { max-width: 100%; border: 1px solid #eee; margin: 0.4em 0; }
code { background: #f4f4f4; padding: 0 3px; } .bad { color: #b00020; } .note { color: #555; font-size: 0.9em; }
"""


def _img(path: Path) -> str:
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    return f'<img alt="{html.escape(path.name)}" title="{html.escape(path.name)}" src="data:image/png;base64,{data}">'


def _link(target: str | None, out_dir: Path) -> str:
    if not target:
        return "-"
    path = Path(target)
    try:
        shown = str(path.relative_to(out_dir))
    except ValueError:
        shown = str(path)
    return f'<a href="{html.escape(shown)}">{html.escape(shown)}</a>'


def _mission_table(summaries: Sequence[Summary], scene: str, mission: str, planners: Sequence[str],
                   metrics: Sequence[str]) -> str:
    from tools.evaluate.figures import metric_label

    cells = {(s.planner, s.metric): s for s in summaries if s.scene == scene and s.mission == mission}
    head = "".join(f"<th>{html.escape(p)}</th>" for p in planners)
    from tools.evaluate.figures import METADATA_COLUMNS

    body: list[str] = []
    meta: list[str] = []
    for metric in metrics:
        if not any((p, metric) in cells for p in planners):
            continue
        row = "".join(f"<td>{format_cell(cells.get((p, metric)))}</td>" for p in planners)
        line = f'<tr><td title="{html.escape(metric)}">{html.escape(metric_label(metric))}</td>{row}</tr>'
        (meta if metric in METADATA_COLUMNS else body).append(line)
    if meta:
        body.append(f"<tr><th colspan='{len(planners) + 1}'>run metadata (not a metric, not tested)</th></tr>")
        body.extend(meta)
    return f"<table><tr><th>metric (mean &plusmn; std over seeds)</th>{head}</tr>{''.join(body)}</table>"


def _summary_table(summaries: Sequence[Summary], rows: Sequence[Mapping[str, Any]], planners: Sequence[str],
                   metrics: Sequence[str]) -> str:
    """One table for the whole study, whatever its number of seeds and missions: per planner, the
    missions completed and, for each top-level metric (``headline_metric``: per-person and
    per-object ones are in the per-mission tables), the mean over the missions of the seeds' means (each mission weighs one)."""
    from tools.evaluate.figures import metric_label

    head = "".join(f"<th>{html.escape(p)}</th>" for p in planners)
    done = []
    for planner in planners:
        mine = [r for r in rows if r["planner"] == planner]
        ok = sum(1 for r in mine if r.get("state") == MissionState.DONE)
        done.append(f"<td>{ok} / {len(mine)}</td>")
    body = [f"<tr><td>missions completed (runs x missions)</td>{''.join(done)}</tr>"]
    from tools.evaluate.table import headline_metric

    for metric in metrics:
        if not headline_metric(metric):
            continue
        cells = []
        for planner in planners:
            means = [s.mean for s in summaries if s.planner == planner and s.metric == metric and math.isfinite(s.mean)]
            cells.append(f"<td>{format_value(sum(means) / len(means))}</td>" if means else "<td>-</td>")
        body.append(f'<tr><td title="{html.escape(metric)}">{html.escape(metric_label(metric))}</td>{"".join(cells)}</tr>')
    return f"<table><tr><th>metric (mean over missions)</th>{head}</tr>{''.join(body)}</table>"


def _tests_table(tests: Sequence[PairedTest]) -> str:
    from tools.evaluate.figures import metric_label

    if not tests:
        return '<p class="note">No paired test: the study needs the social planner and another one on the same ' \
               "missions and seeds.</p>"
    rows = []
    for t in tests:
        sig = math.isfinite(t.p_value) and t.p_value < SIGNIFICANCE
        p = format_value(t.p_value) if math.isfinite(t.p_value) else "- (all pairs equal)"
        rows.append(f'<tr class="{"sig" if sig else ""}"><td>{html.escape(metric_label(t.metric))}</td>'
                    f"<td>{html.escape(t.other)}</td><td>{t.pairs}</td><td>{t.nonzero}</td>"
                    f"<td>{format_value(t.median_difference)}</td><td>{p}</td></tr>")
    return ("<table><tr><th>metric</th><th>vs</th><th>pairs</th><th>pairs that differ</th>"
            f"<th>median of {REFERENCE} &minus; other</th><th>p (Wilcoxon)</th></tr>{''.join(rows)}</table>")


def main_figure(figures: Mapping[str, Sequence[Path]], rows: Sequence[Mapping[str, Any]]) -> Path | None:
    """The trajectories of the mission where the planners' path lengths differ most."""
    paths = list(figures.get("paths", []))
    if not paths:
        return None
    from tools.evaluate.figures import slug

    best, spread = paths[0], -1.0
    for scene, mission in missions_of(rows):
        means = []
        for planner in {r["planner"] for r in rows}:
            values = [float(r["distance_travelled_m"]) for r in rows
                      if (r["scene"], r["mission"], r["planner"]) == (scene, mission, planner)
                      and r.get("state") == MissionState.DONE and math.isfinite(float(r.get("distance_travelled_m", math.nan)))]
            if values:
                means.append(sum(values) / len(values))
        candidate = next((p for p in paths if p.name == f"paths_{slug(scene)}_{slug(mission)}.png"), None)
        if candidate is not None and len(means) > 1 and max(means) - min(means) > spread:
            best, spread = candidate, max(means) - min(means)
    return best


def write_report(out_dir: Path, rows: Sequence[Mapping[str, Any]], runs: Sequence[Mapping[str, Any]],
                 prov: Mapping[str, Any], figures: Mapping[str, Sequence[Path]], planner_order: Sequence[str],
                 pending: int = 0) -> Path:
    """The report, ``summary.csv`` and ``tests.csv`` under ``out_dir``; returns the report's path."""
    from tools.evaluate.table import metric_columns

    from tools.evaluate.figures import METADATA_COLUMNS

    summaries = summarise(rows)
    # Run metadata (the trajectory's sample count...) describes a run; testing it would claim a finding.
    tests = [t for t in paired_tests(rows) if t.metric not in METADATA_COLUMNS]
    write_summary(summaries, out_dir / SUMMARY)
    write_tests(tests, out_dir / TESTS)
    planners = planners_of(rows, planner_order) if rows else list(planner_order)
    metrics = metric_columns(rows)
    parts = [f"<!doctype html><html><head><meta charset='utf-8'><title>chronav evaluate</title>"
             f"<style>{_STYLE}</style></head><body>",
             "<h1>chronav evaluate: planners across scenes and seeds</h1>"]
    parts += _provenance_html(runs, prov, pending)
    main = main_figure(figures, rows)
    if main is not None:
        parts.append(f"<h2>Main figure</h2>{_img(main)}")
    parts.append("<h2>Summary</h2>" + _summary_table(summaries, rows, planners, metrics))
    parts += _per_mission_html(summaries, rows, planners, metrics)
    parts += _tests_html(tests)
    parts += live_prediction_html(runs)       # tools/evaluate/prediction_section.py
    parts += _figures_html(figures, main) if prov.get("figures", True) else [
        "<h2>Figures</h2><p class='note'>Not drawn: the study ran with <code>--no-figures</code>.</p>"]
    parts += _runs_html(runs, out_dir)
    path = out_dir / REPORT
    path.write_text("\n".join(parts), encoding="utf-8")
    return path


def _provenance_html(runs: Sequence[Mapping[str, Any]], prov: Mapping[str, Any], pending: int) -> list[str]:
    """How many runs succeeded, what made them (command, executor, seeds, planners, scene files) and how."""
    from agents.lib.registry import describe

    esc = html.escape
    parts = []
    ok = sum(1 for r in runs if r.get("ok"))
    status = f"{len(runs)} runs, {ok} with every mission done"
    if pending:
        status += f'; <span class="bad">{pending} not run yet (interrupted: continue with --resume)</span>'
    parts.append(f"<p>{status}. Created {esc(str(prov['created']))} by chronav {esc(str(prov['chronav']))}.</p>")
    parts.append("<table>"
                 f"<tr><td>command</td><td><code>{esc(str(prov['command']))}</code></td></tr>"
                 f"<tr><td>executor</td><td>{esc(str(prov['executor']))} (jobs {prov['jobs']})</td></tr>"
                 f"<tr><td>seeds</td><td>{esc(', '.join(map(str, prov['seeds'])))}</td></tr>"
                 + "".join(f"<tr><td>planner <b>{esc(p)}</b></td><td>{esc(describe('planner', p))}</td></tr>"
                           for p in prov["planners"])
                 + "".join(f"<tr><td>scene {esc(name)}</td><td><code>{esc(f['file'])}</code><br>sha256 "
                           f"<code>{f['sha256']}</code></td></tr>"
                           for name, files in prov["scenes"].items() for f in files)
                 + "</table>")
    how = ("the six agents in one process, stepped in lockstep on one graph (metrics identical to a full launch's)"
           if prov.get("mode") == "in-process" else "a full launch of the six agents as processes")
    parts.append(f'<p class="note">Each run is {how}; metrics are those of '
                 "<code>chronav metrics SCENE TRAJ.csv</code> on each mission's stretch of the run's trajectory "
                 "(<code>missions/&lt;mission&gt;.csv</code> in the run directory) with the people's "
                 "trajectories over the same stretch beside it (<code>&lt;mission&gt;.people.csv</code>: the "
                 "metrics among moving people, <code>dynamic.*</code>), against the world at the mission's "
                 "start. Table: <code>table.parquet</code> / <code>table.csv</code>; the numbers of the "
                 "tables below: <code>summary.csv</code>, <code>tests.csv</code>.</p>")
    return parts


def _per_mission_html(summaries: Sequence[Summary], rows: Sequence[Mapping[str, Any]], planners: Sequence[str],
                      metrics: Sequence[str]) -> list[str]:
    """One folded table per scene and mission: mean and std over the seeds."""
    esc = html.escape
    parts = ["<h2>Per mission: mean &plusmn; std over the seeds</h2>"]
    for scene, mission in missions_of(rows):
        done = sum(1 for r in rows if (r["scene"], r["mission"]) == (scene, mission) and r.get("state") == MissionState.DONE)
        total = sum(1 for r in rows if (r["scene"], r["mission"]) == (scene, mission))
        # Folded: with many missions and metrics the details would bury the summary.
        parts.append(f"<details><summary><b>{esc(scene)} / {esc(mission)}</b> <span class='note'>({done} of "
                     f"{total} runs completed it)</span></summary>")
        parts.append(_mission_table(summaries, scene, mission, planners, metrics) + "</details>")
    return parts


def _tests_html(tests: Sequence[PairedTest]) -> list[str]:
    """The paired tests against the reference planner, with how to read them."""
    return [f"<h2>Is {REFERENCE} different? Paired tests per metric</h2>"
            "<p class='note'>Wilcoxon signed-rank test (two-sided, scipy.stats.wilcoxon, zero differences "
            f"dropped), pairs = the same scene, mission and seed; green: p &lt; {SIGNIFICANCE}. With few "
            "pairs the smallest attainable p is large (6 pairs: 0.031).</p>",
            _tests_table(tests)]


def _figures_html(figures: Mapping[str, Sequence[Path]], main: Path | None) -> list[str]:
    """R(t), the trajectories other than the main figure's, and the metrics by planner."""
    parts = ["<h2>R(t) over the day</h2>" + "".join(_img(p) for p in figures.get("r_of_t", []))]
    others = [p for p in figures.get("paths", []) if p != main]   # the main figure is shown once, above
    if others:
        parts.append("<h2>Trajectories of the other missions</h2>" + "".join(_img(p) for p in others))
    parts.append("<h2>Metrics by planner across seeds</h2><p class='note'>Every seed is a dot; box plots need at "
                 "least 5 seeds per planner, below that a bar marks the mean.</p>"
                 + "".join(_img(p) for p in figures.get("boxes", [])))
    return parts


def _runs_html(runs: Sequence[Mapping[str, Any]], out_dir: Path) -> list[str]:
    """Every run, folded: outcome (the error on hover), wall time, host, links to recording and directory."""
    esc = html.escape
    parts = [f"<h2>Runs</h2><details><summary>{len(runs)} runs (click to show)</summary>"
             "<table><tr><th>scene</th><th>planner</th><th>seed</th><th>outcome</th>"
             "<th>wall s</th><th>host</th><th>recording</th><th>run directory</th></tr>"]
    for run in sorted(runs, key=lambda r: (r["spec"]["scene"], r["spec"]["planner"], r["spec"]["seed"])):
        spec = run["spec"]
        outcome = esc(str(run.get("outcome")))
        if run.get("error"):
            outcome = f'<span class="bad" title="{esc(str(run["error"]))}">{outcome}</span>'
        parts.append(f"<tr><td>{esc(Path(spec['scene']).stem)}</td><td>{esc(spec['planner'])}</td>"
                     f"<td>{spec['seed']}</td><td>{outcome}</td><td>{float(run.get('wall_s', 0.0)):.1f}</td>"
                     f"<td>{esc(str(run.get('host')))}</td><td>{_link(run.get('rrd'), out_dir)}</td>"
                     f"<td>{_link(run.get('run_dir'), out_dir)}</td></tr>")
    parts.append("</table></details><p class='note'>Open a recording with <code>rerun FILE.rrd</code>.</p>"
                 "</body></html>")
    return parts
