"""The Rerun viewer layout shipped with every recording, scaled to the scene, and its legend.

Why a blueprint: without it the viewer guesses a layout from entity paths and the map, the
time series and the DSR graph end up in tiny tabs.  With it, a user opening a run sees the map
(world, belief and decision layers) framed on the whole building, R(t) over the whole day, the
DSR graph, a legend of every colour, and the agents' events with their full text, every time
axis on the scene's clock (the ``clock`` timeline, agents/runtime/recording.py).

Why the layout depends on the building's shape: a long building (center_day is 26 x 10 m) in a
panel beside the other views fills a third of it; above them it fills the width.
"""

from __future__ import annotations

from functools import partial
from typing import Any

from agents.runtime.drawing import bodies, social_map
from agents.runtime.recording import CLOCK_TIMELINE, clock_epoch_s

MAP_MARGIN_M = 0.6
WIDE_ASPECT = 1.6   # width / height above which the map goes on top, across the whole window


def map_bounds(scene: Any) -> tuple[float, float, float, float]:
    """(xmin, ymin, xmax, ymax) the map view is framed on: the building, a margin, and room
    above it for the decision stamp (social_navigation puts it at ymax + 0.5)."""
    xmin, ymin, xmax, ymax = scene.bounds
    return xmin - MAP_MARGIN_M, ymin - MAP_MARGIN_M, xmax + MAP_MARGIN_M, ymax + MAP_MARGIN_M + 0.5


def blueprint(scene: Any | None = None) -> Any:
    import rerun.blueprint as rrb
    from rerun.blueprint.encodings import TextLogColumn, TimelineColumn

    bounds = None
    if scene is not None:
        xmin, ymin, xmax, ymax = map_bounds(scene)
        # The view is y-down and ``world`` flips y (world_frame): world y maps to -y.
        bounds = rrb.VisualBounds2D(x_range=[xmin, xmax], y_range=[-ymax, -ymin])
    map_view = rrb.Spatial2DView(origin="/", contents=["/world/**"], visual_bounds=bounds,
                                 name="Map: world (true poses) · belief (tracked people) · decision (the map and path used)")
    whole_day = rrb.VisibleTimeRange(CLOCK_TIMELINE, start=rrb.TimeRangeBoundary.infinite(),
                                     end=rrb.TimeRangeBoundary.infinite())
    day_axis = None
    if scene is not None:   # the x axis spans the scene's day, whatever the cursor
        epoch_ns = int(round(clock_epoch_s(scene.clock.date))) * 1_000_000_000
        day_axis = rrb.TimeAxis(view_range=rrb.TimeRange(
            start=rrb.TimeRangeBoundary.absolute(nanos=epoch_ns + int(scene.clock.start_s * 1e9)),
            end=rrb.TimeRangeBoundary.absolute(nanos=epoch_ns + int(scene.clock.end_s * 1e9))))
    series = partial(rrb.TimeSeriesView, time_ranges=[whole_day], axis_x=day_axis)
    r_of_t = series(origin="metrics/objects", name="R(t) per object (whole day)", plot_legend=rrb.Corner2D.LeftTop)
    robot = series(origin="metrics/robot", name="Robot speed (m/s)")
    missions = series(origin="metrics/missions", name="Mission metrics")
    graph = rrb.GraphView(origin="dsr", name="DSR (rooms, objects, activities, people, missions)")
    legend = rrb.Spatial2DView(origin="legend", name="Legend", visual_bounds=rrb.VisualBounds2D(
        x_range=[-0.4, LEGEND_WIDTH], y_range=[-0.7, LEGEND_ROWS * LEGEND_ROW_M - 0.3]))
    # Every event's text starts with its clock time and agent (Recorder.event): the viewer's own
    # time columns (a date-time too wide for the column, "+34 513.80" for sim_time) are hidden.
    events = rrb.TextLogView(origin="events", name="Agent events (clock time, agent: message)",
                             columns=rrb.archetypes.TextLogColumns(
                                 timeline_columns=[TimelineColumn(CLOCK_TIMELINE, visible=False),
                                                   TimelineColumn("sim_time", visible=False),
                                                   TimelineColumn("log_time", visible=False)],
                                 text_log_columns=[TextLogColumn("LogLevel"), TextLogColumn("Body"),
                                                   TextLogColumn("EntityPath", visible=False)]))
    wide = scene is not None and _aspect(scene) >= WIDE_ASPECT
    if wide:
        body = rrb.Vertical(
            map_view,
            rrb.Horizontal(rrb.Vertical(r_of_t, rrb.Tabs(robot, missions), row_shares=[3, 2]), graph, legend,
                           column_shares=[3, 3, 2]),
            events,
            row_shares=[6, 4, 2],
        )
    else:
        body = rrb.Vertical(
            rrb.Horizontal(map_view, rrb.Vertical(r_of_t, rrb.Tabs(robot, missions), graph, row_shares=[2, 1, 3]),
                           legend, column_shares=[6, 3, 2]),
            events,
            row_shares=[4, 1],
        )
    return rrb.Blueprint(body, rrb.TimePanel(timeline=CLOCK_TIMELINE, state="collapsed"), collapse_panels=True)


def _aspect(scene: Any) -> float:
    xmin, ymin, xmax, ymax = map_bounds(scene)
    return (xmax - xmin) / max(ymax - ymin, 1e-6)


def world_frame(recorder: Any) -> None:
    """Maps are y-up; Rerun's 2-D views are y-down (image convention): flip once at ``world``."""
    import rerun as rr

    recorder.log("world", rr.Transform3D(mat3x3=[[1, 0, 0], [0, -1, 0], [0, 0, 1]]), static=True)


LEGEND: list[tuple[str, str, tuple[int, ...]]] = [
    # (kind, text, colour): kind "point" a disc, "line" a stroke, "box" a filled patch
    ("point", "robot (arrow: heading)", bodies.ROBOT_RGB),
    ("line", "robot trail, last 3 min", bodies.ROBOT_TRAIL_RGBA),
    ("point", "person, as tracked", bodies.PEOPLE_RGB),
    ("point", "person, true position", bodies.TRUTH_RGB),
    ("point", "walker, predicted", bodies.PREDICTED_RGBA),
    ("line", "planned path", social_map.PATH_RGB),
    ("line", "elastic band", social_map.BAND_RGB),
    ("box", "free floor", (0, 0, 0, 255)),
    ("box", "wall (inflated), outside", (70, 70, 70, 255)),
    ("line", "intimate zone (blocked)", social_map.ZONE_COLOURS["intimate"]),
    ("line", "personal zone (cost 4)", social_map.ZONE_COLOURS["personal"]),
    ("line", "social zone (cost 2)", social_map.ZONE_COLOURS["social"]),
    ("box", "in use: forbidden", (220, 40, 40, 200)),
    *[("box", f"interaction R {lo:.1f}-{hi:.1f}", (*rgb, 200))
      for lo, hi, rgb in zip((1.5, 2.0, 2.5, 3.0), (2.0, 2.5, 3.0, 3.5), social_map.BAND_COLOURS_RGB, strict=True)],
]
LEGEND_ROWS = 9            # two columns of nine: legible in a panel a quarter of the window wide
LEGEND_ROW_M = 1.0
LEGEND_COLUMN_M = 10.5     # legend units between the two columns
LEGEND_WIDTH = 2 * LEGEND_COLUMN_M
LEGEND_TEXT_M = 4.6        # labels are centred on their anchor: this far right of a swatch they clear it


def log_legend(recorder: Any, scene: Any = None) -> None:
    """Static swatches with their meaning under ``legend`` (the Legend panel), in two columns."""
    del scene
    if not recorder.enabled:
        return
    import rerun as rr

    for i, (kind, text, colour) in enumerate(LEGEND):
        x0, y = (i // LEGEND_ROWS) * LEGEND_COLUMN_M, (i % LEGEND_ROWS) * LEGEND_ROW_M
        path = f"legend/{i:02d}"
        swatch: rr.Points2D | rr.LineStrips2D
        if kind == "point":
            swatch = rr.Points2D([[x0 + 0.4, y]], radii=0.3, colors=[colour])
        else:   # a stroke, or a thick one as a filled patch (2-D boxes are outlines only)
            swatch = rr.LineStrips2D([[[x0, y], [x0 + 0.8, y]]], colors=[colour], radii=0.08 if kind == "line" else 0.3)
        recorder.log(f"{path}/swatch", swatch, static=True)
        recorder.log(f"{path}/text", rr.Points2D([[x0 + LEGEND_TEXT_M, y]], radii=0.01, colors=[(230, 230, 230)],
                                                 labels=[text]), static=True)
