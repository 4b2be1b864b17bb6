"""The figures of a study (matplotlib, Agg backend: no display needed).

- ``box_<metric>.png``: per metric, one panel per mission, the seeds of each planner as dots;
  with at least ``BOX_MIN_SEEDS`` seeds a box over them, below that a strip plot (dots and their
  mean): a box of 2 points draws quartiles that do not exist.  The y axis is the metric with
  its unit; run metadata (``METADATA_COLUMNS``, e.g. the trajectory's sample count) is no metric
  and gets no figure;
- ``paths_<scene>_<mission>.png``: every planner's driven trajectories over the map at the
  mission's time (walls, object footprints, interaction spaces shaded by R, the people's
  intimate / personal / social zones, the people), from the offline world (agents/world/offline.py)
  so the picture is the world the metrics were measured against;
- ``r_of_t_<scene>.png``: each object's R(t) over the scene's day, missions marked, clock ticks
  spaced for the day's length.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from agents.world.vocabulary import MissionState
from tools.evaluate.stats import MissionKey, done_rows, missions_of, planners_of

#: planner colours by the planner's place in the study (colour-blind safe: Okabe-Ito), so every
#: figure of a report gives a planner the same colour and any installed planner gets one
PALETTE = ("#0072B2", "#D55E00", "#009E73", "#56B4E9", "#CC79A7", "#E69F00", "#F0E442", "#000000", "#999999")
ZONE_COLOURS = {"social": "#FFF3B0", "personal": "#FFC971", "intimate": "#E4572E"}
DPI = 110
BOX_MIN_SEEDS = 5
#: columns of the table that describe a run rather than measure it: shown, never plotted or tested
METADATA_COLUMNS = frozenset({"samples"})

def _catalogue_label(metric: str) -> str:
    from agents.lib.metrics.metric_catalog import column_label

    return column_label(metric)


def _pyplot() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def metric_label(metric: str) -> str:
    """A reader's name for a metric column with its unit (metric_catalog.py: the same names as
    `chronav metrics` and the demo table; unknown columns keep their column name)."""
    if metric == "samples":
        return "trajectory samples (count)"
    return _catalogue_label(metric)


def slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", text).strip("_")


def planner_colour(planner: str, planners: Sequence[str]) -> str:
    """The colour of ``planner`` among the study's ``planners`` (their order is the study's)."""
    return PALETTE[list(planners).index(planner) % len(PALETTE)] if planner in planners else "#444444"


def _clock(t_s: float) -> str:
    from scenes.clock import format_clock

    return format_clock(t_s)


# ---------------------------------------------------------------------------------------------
# Box plots.
# ---------------------------------------------------------------------------------------------

def box_plot(rows: Sequence[Mapping[str, Any]], metric: str, planners: Sequence[str], path: Path) -> Path | None:
    """One panel per mission, one box per planner over the seeds; None if the metric has no value."""
    plt = _pyplot()
    missions = [m for m in missions_of(rows) if any(_values(rows, m, p, metric) is not None for p in planners)]
    if not missions:
        return None
    cols = min(4, len(missions))
    nrows = math.ceil(len(missions) / cols)
    fig, axes = plt.subplots(nrows, cols, figsize=(max(4.8, 3.2 * cols + 0.6), 3.3 * nrows + 0.5), squeeze=False)
    for ax in axes.flat[len(missions):]:
        ax.set_visible(False)
    for ax, (scene, mission) in zip(axes.flat, missions, strict=False):
        data, labels, colours = [], [], []
        for planner in planners:
            values = _values(rows, (scene, mission), planner, metric)
            data.append(values if values is not None else np.array([]))
            labels.append(planner)
            colours.append(planner_colour(planner, planners))
        positions = np.arange(1, len(planners) + 1)
        present = [i for i, d in enumerate(data) if len(d)]
        boxed = [i for i in present if len(data[i]) >= BOX_MIN_SEEDS]
        if boxed:
            boxes = ax.boxplot([data[i] for i in boxed], positions=positions[boxed], widths=0.55,
                               patch_artist=True, showfliers=False, medianprops={"color": "black"})
            for patch, i in zip(boxes["boxes"], boxed, strict=True):
                patch.set_facecolor(colours[i])
                patch.set_alpha(0.45)
        jitter = np.random.default_rng(0)    # the same dots every time the report is built
        for i in present:
            xs = positions[i] + jitter.uniform(-0.12, 0.12, len(data[i]))
            ax.scatter(xs, data[i], s=22, color=colours[i], edgecolor="black", linewidth=0.4, zorder=3)
            if i not in boxed:   # strip plot: the mean as a short bar across the dots
                ax.hlines(float(np.mean(data[i])), positions[i] - 0.25, positions[i] + 0.25, color="black",
                          linewidth=1.5, zorder=4)
        ax.set_xticks(positions, labels, rotation=30, ha="right", fontsize=9)
        ax.set_xlim(0.4, len(planners) + 0.6)
        ax.set_ylabel(metric_label(metric), fontsize=8)
        ax.set_title(f"{scene} / {mission}" if len({s for s, _ in missions}) > 1 else mission, fontsize=10)
        ax.grid(axis="y", alpha=0.3)
        ax.tick_params(axis="y", labelsize=8)
    counts = [len(d) for m in missions for p in planners if (d := _values(rows, m, p, metric)) is not None]
    kind = "dots: seeds; boxes: quartiles" if counts and min(counts) >= BOX_MIN_SEEDS else \
        f"dots: seeds; bar: mean (boxes from {BOX_MIN_SEEDS} seeds)"
    fig.suptitle(metric_label(metric), fontsize=11)
    fig.text(0.5, 0.005, kind, ha="center", va="bottom", fontsize=8, color="#555555")
    # Fixed margins, not tight_layout: laying out draws every figure twice (most of the report's time).
    fig.subplots_adjust(left=0.1 if cols > 1 else 0.2, right=0.98, bottom=0.22 / nrows, top=1 - 0.14 / nrows,
                        wspace=0.35, hspace=0.55)
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return path


def _values(rows: Sequence[Mapping[str, Any]], mission: MissionKey, planner: str, metric: str) -> np.ndarray | None:
    values = np.array([float(r.get(metric, math.nan)) for r in done_rows(rows)
                       if (r["scene"], r["mission"]) == mission and r["planner"] == planner], dtype=float)
    values = values[np.isfinite(values)]
    return values if len(values) else None


# ---------------------------------------------------------------------------------------------
# Trajectories over the map.
# ---------------------------------------------------------------------------------------------

def _polygons(geometry: Any) -> list[Any]:
    if geometry is None or geometry.is_empty:
        return []
    if geometry.geom_type == "Polygon":
        return [geometry]
    return [g for part in getattr(geometry, "geoms", []) for g in _polygons(part)]


def _fill(ax: Any, geometry: Any, **style: Any) -> None:
    for polygon in _polygons(geometry):
        xs, ys = polygon.exterior.xy
        ax.fill(xs, ys, **style)


def draw_world(ax: Any, maps: Any, t_s: float) -> None:
    """The map at ``t_s`` as the metrics see it: rooms, zones, interaction spaces, footprints, walls, people."""
    scene = maps.world.scene
    smap = maps.at(t_s)
    for room in scene.rooms:
        xs, ys = zip(*[(p[0], p[1]) for p in room.polygon], strict=True)
        ax.fill(xs, ys, color="#F4F4F4", zorder=0)
    r_min, r_max = smap.params.chronemics.r_min, smap.params.chronemics.r_max
    for space in smap.object_spaces:
        level = 0.0 if r_max <= r_min else (min(max(space.r, r_min), r_max) - r_min) / (r_max - r_min)
        _fill(ax, space.interaction, color="#F28E2B", alpha=0.12 + 0.38 * level, zorder=1, linewidth=0)
        centroid = space.interaction.centroid
        ax.annotate(f"{space.name}\nR={space.r:.2f}" + (" (in use)" if space.active else ""),
                    (centroid.x, centroid.y), ha="center", va="center", fontsize=7, color="#7A3E00", zorder=6)
    zones = smap.zone_polygons()
    for name in ("social", "personal", "intimate"):
        _fill(ax, zones.get(name), color=ZONE_COLOURS[name], alpha=0.75, zorder=2, linewidth=0)
    for space in smap.object_spaces:
        _fill(ax, space.footprint, color="#8C8C8C", zorder=3)
    for wall in scene.walls:
        xs, ys = zip(*[(p[0], p[1]) for p in wall], strict=True)
        ax.plot(xs, ys, color="black", linewidth=2.0, zorder=4, solid_capstyle="round")
    for person in smap.people:
        ax.add_patch(_circle((person.x, person.y), 0.22, facecolor="#5B5B5B", edgecolor="white", zorder=5))
        ax.annotate("", (person.x + 0.45 * math.cos(person.theta), person.y + 0.45 * math.sin(person.theta)),
                    (person.x, person.y), arrowprops={"arrowstyle": "-|>", "color": "#5B5B5B", "lw": 1.2}, zorder=5)


def _circle(xy: tuple[float, float], radius: float, **style: Any) -> Any:
    from matplotlib.patches import Circle

    return Circle(xy, radius, **style)


def _read_xy(path: str | None) -> np.ndarray | None:
    if not path or not Path(path).exists():
        return None
    from agents.lib.metrics.metrics import MetricsInputError, read_trajectory_csv

    try:
        return read_trajectory_csv(path)[:, 1:3]
    except MetricsInputError:
        return None


def paths_figure(rows: Sequence[Mapping[str, Any]], mission: MissionKey, maps: Any, planners: Sequence[str],
                 path: Path) -> Path:
    """Every planner's trajectories (one line per seed) over the map at the mission's time."""
    plt = _pyplot()
    from matplotlib.artist import Artist
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    mine = [r for r in rows if (r["scene"], r["mission"]) == mission]
    times = [float(r["at_s"]) for r in mine if r.get("at_s") is not None and math.isfinite(float(r["at_s"]))]
    t_s = float(np.median(times)) if times else float(mine[0]["mission_time_s"])
    xmin, ymin, xmax, ymax = maps.world.scene.bounds
    width = 9.5
    fig, ax = plt.subplots(figsize=(width, max(3.0, 0.7 * width * (ymax - ymin) / (xmax - xmin)) + 0.8))
    draw_world(ax, maps, t_s)
    handles: list[Artist] = []
    for order, planner in enumerate(planners):
        colour = planner_colour(planner, planners)
        # Planners often drive the same way: each is drawn thinner than the one before, on top of
        # it, so coinciding paths show as nested stripes instead of hiding each other.
        width = max(1.0, 5.0 - 3.5 * order / max(1, len(planners) - 1))
        drawn = 0
        for row in (r for r in mine if r["planner"] == planner):
            xy = _read_xy(row.get("trajectory_csv"))
            if xy is None:
                continue
            ax.plot(xy[:, 0], xy[:, 1], color=colour, linewidth=width, alpha=0.9, zorder=7 + 0.01 * order,
                    solid_capstyle="round")
            ax.plot(*xy[0], marker="o", color=colour, markersize=5, zorder=8)
            ax.plot(*xy[-1], marker="*", color=colour, markersize=11, markeredgecolor="black", zorder=8)
            drawn += 1
        failed = sum(1 for r in mine if r["planner"] == planner and r.get("state") != MissionState.DONE)
        note = f" ({drawn} run{'s' if drawn != 1 else ''}" + (f", {failed} not done" if failed else "") + ")"
        handles.append(Line2D([], [], color=colour, linewidth=width, label=planner + note))
    handles += [Patch(color=ZONE_COLOURS[z], label=f"{z} zone") for z in ("intimate", "personal", "social")]
    handles.append(Patch(color="#F28E2B", alpha=0.45, label="interaction space (darker: higher R)"))
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=9, frameon=False)
    ax.set_xlim(xmin - 0.2, xmax + 0.2)
    ax.set_ylim(ymin - 0.2, ymax + 0.2)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(f"{mission[0]} / {mission[1]}: trajectories at {_clock(t_s)} (start o, goal *)", fontsize=11)
    fig.savefig(path, dpi=DPI, bbox_inches="tight")
    plt.close(fig)
    return path


# ---------------------------------------------------------------------------------------------
# R(t) over the day.
# ---------------------------------------------------------------------------------------------

def r_curves(maps: Any, step_s: float = 60.0) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Each object's R over the scene's day, as the agenda agent computes it (agenda changes included)."""
    from agents.world.dsr_writers import object_r
    from agents.world.timeline import agenda_at

    scene = maps.world.scene
    params = maps.nav.params.chronemics
    times = np.arange(scene.clock.start_s, scene.clock.end_s + step_s / 2, step_s)
    curves = {obj.name: np.empty(len(times)) for obj in scene.objects}
    for i, t in enumerate(times):
        day = agenda_at(maps.world, float(t))
        for obj in scene.objects:
            curves[obj.name][i] = object_r(day, obj.name, float(t), params)[0]
    return times, curves


TICK_STEPS_S = (300.0, 600.0, 900.0, 1800.0, 3600.0, 7200.0, 10800.0, 21600.0)


def clock_ticks(start_s: float, end_s: float, at_most: int = 12) -> np.ndarray:
    """Clock ticks on round times, the finest step that gives at most ``at_most`` of them (a
    90-minute day on whole hours had two labels; a nine-hour day gets hourly ones)."""
    for step in TICK_STEPS_S:
        ticks = np.arange(math.ceil(start_s / step) * step, end_s + 1e-6, step)
        if len(ticks) <= at_most:
            return ticks
    return ticks


def _hhmm(t_s: float) -> str:
    whole = int(round(t_s))
    return f"{whole // 3600:02d}:{whole % 3600 // 60:02d}"


def study_metrics(rows: Sequence[Mapping[str, Any]]) -> list[str]:
    """The table's metric columns that measure something (METADATA_COLUMNS left out)."""
    from tools.evaluate.table import metric_columns

    return [m for m in metric_columns(rows) if m not in METADATA_COLUMNS]


def r_of_t_figure(maps: Any, missions: Sequence[tuple[str, float]], path: Path) -> Path:
    """R(t) per object over the day; a dashed line at each mission's time."""
    plt = _pyplot()
    times, curves = r_curves(maps)
    fig, ax = plt.subplots(figsize=(10, 3.8))
    hours = times / 3600.0
    for name, values in curves.items():
        ax.plot(hours, values, linewidth=2.0, label=name)
    top = max((float(v.max()) for v in curves.values()), default=1.0)
    for mission, t_s in missions:
        ax.axvline(t_s / 3600.0, color="#555555", linestyle="--", linewidth=1.0)
        ax.annotate(f"{mission}\n{_clock(t_s)}", (t_s / 3600.0, top * 1.02), ha="center", va="bottom", fontsize=8)
    ticks = clock_ticks(times[0], times[-1])
    ax.set_xticks(ticks / 3600.0, [_hhmm(t) for t in ticks])
    ax.set_xlim(hours[0], hours[-1])
    ax.set_ylim(0, top * 1.25)
    ax.set_xlabel("time of day (HH:MM, the scene's clock)")
    ax.set_ylabel("R(t): interaction-space cost\n(cost units, as the grid's)")
    ax.set_title(f"{maps.world.scene.name}: R(t) of each object over the day (dashed: missions)", fontsize=11)
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=9, frameon=False)
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return path


def all_figures(rows: Sequence[Mapping[str, Any]], scenes: Mapping[str, Any], out_dir: Path,
                planner_order: Sequence[str]) -> dict[str, list[Path]]:
    """Every figure of the study under ``out_dir``: {"paths": [...], "r_of_t": [...], "boxes": [...]}."""
    planners = planners_of(rows, planner_order)
    figures: dict[str, list[Path]] = {"paths": [], "r_of_t": [], "boxes": []}
    for scene, mission in missions_of(rows):
        if scene in scenes and any(r.get("trajectory_csv") for r in rows if (r["scene"], r["mission"]) == (scene, mission)):
            figures["paths"].append(paths_figure(rows, (scene, mission), scenes[scene], planners,
                                                 out_dir / f"paths_{slug(scene)}_{slug(mission)}.png"))
    for scene, maps in scenes.items():
        times: dict[str, float] = {}
        for row in rows:
            if row["scene"] == scene:
                times.setdefault(row["mission"], float(row["mission_time_s"]))
        figures["r_of_t"].append(r_of_t_figure(maps, sorted(times.items(), key=lambda kv: kv[1]),
                                               out_dir / f"r_of_t_{slug(scene)}.png"))
    for metric in study_metrics(rows):
        made = box_plot(rows, metric, planners, out_dir / f"box_{slug(metric)}.png")
        if made is not None:
            figures["boxes"].append(made)
    return figures
