"""A study's table as Markdown: the tables docs/baselines.md shows, regenerated from a study's
``table.parquet`` (``python -m tools.evaluate.markdown STUDY_DIR``).

Why a separate printer: the HTML report (report.py) holds every metric, figure and test; a doc
needs the few headline numbers a reader compares methods on (HuNavSim's time to goal, path length,
minimum distance to people, intimate and personal intrusions, collisions, and success), computed
by the same functions (stats.py) and named as `chronav metrics` names them (metric_catalog), so
the doc cannot drift from what the study measured.  Methods are planner x controller pairs named
as the report names them (sweep.method_label).
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from agents.world.vocabulary import MissionState

#: the headline columns, in the order shown: (table column, short header)
HEADLINE: tuple[tuple[str, str], ...] = (
    ("duration_s", "time to goal s"),
    ("distance_travelled_m", "path length m"),
    ("dynamic.min_distance_to_people_m", "min dist. to people m"),
    ("dynamic.intimate_intrusions_percent", "intimate intrusions %"),
    ("dynamic.personal_intrusions_percent", "personal intrusions %"),
    ("collisions", "collisions"),
)
COLLISION_COLUMNS = ("dynamic.robot_on_person_collisions", "dynamic.person_on_robot_collisions")
P_SHOWN = 0.05


def with_methods(rows: Sequence[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """The rows with ``planner`` replaced by the report's method name, and a ``collisions`` column
    (both directions summed, NaN when neither was measured)."""
    from tools.evaluate.sweep import DEFAULT_CONTROLLER, method_label

    out = []
    for row in rows:
        counts = [float(row.get(c, math.nan)) for c in COLLISION_COLUMNS]
        finite = [c for c in counts if math.isfinite(c)]
        out.append({**row, "planner": method_label(row["planner"], row.get("controller") or DEFAULT_CONTROLLER),
                    "collisions": sum(finite) if finite else math.nan})
    return out


def methods_of(rows: Sequence[Mapping[str, Any]]) -> list[str]:
    seen: dict[str, None] = {}
    for row in rows:
        seen.setdefault(row["planner"], None)
    return list(seen)


def _cell(values: list[float]) -> str:
    finite = [v for v in values if math.isfinite(v)]
    if not finite:
        return "-"
    mean = sum(finite) / len(finite)
    if len(finite) < 2:
        return f"{mean:.2f}"
    std = math.sqrt(sum((v - mean) ** 2 for v in finite) / (len(finite) - 1))
    return f"{mean:.2f} ± {std:.2f}"


def scene_table(rows: Sequence[Mapping[str, Any]], scene: str) -> list[str]:
    """Per method on ``scene``: missions done of those run, then each headline metric's mean ± std
    over the done missions and seeds."""
    lines = ["| method | done | " + " | ".join(h for _, h in HEADLINE) + " |",
             "|---|---|" + "---|" * len(HEADLINE)]
    mine = [r for r in rows if r["scene"] == scene]
    for method in methods_of(mine):
        runs = [r for r in mine if r["planner"] == method]
        done = [r for r in runs if r.get("state") == MissionState.DONE]
        cells = [_cell([float(r.get(column, math.nan)) for r in done]) for column, _ in HEADLINE]
        lines.append(f"| {method} | {len(done)}/{len(runs)} | " + " | ".join(cells) + " |")
    return lines


def mission_table(rows: Sequence[Mapping[str, Any]], scene: str) -> list[str]:
    """Per mission of ``scene`` and method: done of the seeds, and mean time to goal when done."""
    from tools.evaluate.stats import missions_of

    mine = [r for r in rows if r["scene"] == scene]
    methods = methods_of(mine)
    lines = ["| mission | " + " | ".join(methods) + " |", "|---|" + "---|" * len(methods)]
    for _, mission in (key for key in missions_of(mine) if key[0] == scene):
        cells = []
        for method in methods:
            runs = [r for r in mine if r["mission"] == mission and r["planner"] == method]
            done = [r for r in runs if r.get("state") == MissionState.DONE]
            time = _cell([float(r.get("duration_s", math.nan)) for r in done]).split(" ±")[0]
            cells.append(f"{len(done)}/{len(runs)}" + (f", {time} s" if time != "-" else ""))   # a wait: no drive
        lines.append(f"| {mission} | " + " | ".join(cells) + " |")
    return lines


def tests_table(rows: Sequence[Mapping[str, Any]]) -> list[str]:
    """The paired Wilcoxon tests of ``social`` (with the elastic band) against each other method
    on the headline metrics, those with p < 0.05."""
    from tools.evaluate.stats import REFERENCE, paired_tests

    headers = dict(HEADLINE)
    lines = ["| metric | social vs | pairs | median difference | p |", "|---|---|---|---|---|"]
    for test in paired_tests(rows, REFERENCE):
        if test.metric in headers and math.isfinite(test.p_value) and test.p_value < P_SHOWN:
            lines.append(f"| {headers[test.metric]} | {test.other} | {test.pairs} | "
                         f"{test.median_difference:+.3g} | {test.p_value:.3g} |")
    return lines


def study_markdown(study_dir: Path) -> str:
    from tools.evaluate.table import TABLE_STEM, read_table

    rows = with_methods(read_table(study_dir / f"{TABLE_STEM}.parquet"))
    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    seeds = sorted({int(r["seed"]) for r in rows})
    out = [f"{len(rows)} missions over {len(seeds)} seeds ({', '.join(map(str, seeds))}); mean ± std over the "
           "done missions and seeds; `done`: missions done of those run.", ""]
    for scene in scenes:
        out += [f"### {scene}", "", *scene_table(rows, scene), "", "Per mission (done of the seeds, mean time to goal):",
                "", *mission_table(rows, scene), ""]
    out += [f"### Paired tests (p < {P_SHOWN})", "", *tests_table(rows), ""]
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("study", type=Path, help="a study's --out directory (holds table.parquet)")
    options = parser.parse_args(argv)
    try:
        sys.stdout.write(study_markdown(options.study))
    except (OSError, ValueError) as exc:
        sys.stderr.write(f"error: {options.study}: {exc}; give the --out directory of a finished `chronav evaluate`\n")
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
