"""The Rerun viewer layout shipped with every recording.

Why a blueprint: without it the viewer guesses a layout from entity paths and the map, the
time series and the DSR graph end up in tiny tabs. With it, a user opening a run sees the map
(walls, zones, interaction spaces, paths, robot, laser) large, and metrics, R(t), the DSR graph
and agent events beside it.
"""

from __future__ import annotations

from typing import Any


def blueprint() -> Any:
    import rerun.blueprint as rrb

    return rrb.Blueprint(
        rrb.Horizontal(
            # Origin "/" so that the y-up transform logged at "world" applies (see world_frame()).
            rrb.Spatial2DView(origin="/", contents=["/world/**"], name="Social map"),
            rrb.Vertical(
                rrb.TimeSeriesView(origin="metrics/objects", name="R(t) per object"),
                rrb.Tabs(rrb.TimeSeriesView(origin="metrics/robot", name="Robot"),
                         rrb.TimeSeriesView(origin="metrics/missions", name="Mission metrics")),
                rrb.GraphView(origin="dsr", name="DSR graph"),
                rrb.TextLogView(origin="events", name="Agent events"),
                row_shares=[2, 2, 3, 2],
            ),
            column_shares=[3, 2],
        ),
        collapse_panels=True,
    )


def world_frame(recorder: Any) -> None:
    """Maps are y-up; Rerun's 2-D views are y-down (image convention): flip once at ``world``."""
    import rerun as rr

    recorder.log("world", rr.Transform3D(mat3x3=[[1, 0, 0], [0, -1, 0], [0, 0, 1]]), static=True)
