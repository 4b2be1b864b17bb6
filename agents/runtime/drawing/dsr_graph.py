"""Log the DSR itself to Rerun as a graph view (nodes coloured by type, typed edges).

Why throttled and change-driven: the graph changes on every robot pose; a graph view needs the
*structure* (nodes, typed edges), so we log only when that structure changes, at most once per
``min_period_s`` of sim time.
"""

from __future__ import annotations

from typing import Any

TYPE_COLOURS: dict[str, tuple[int, int, int]] = {
    "world": (120, 120, 120), "room": (90, 160, 90), "door": (150, 200, 150), "person": (240, 160, 40),
    "object": (160, 90, 200), "robot": (30, 120, 255), "activity": (230, 60, 60), "mission": (20, 180, 180),
    "intention": (100, 220, 220), "clock": (200, 200, 200),
}
HIDDEN_EDGES = {"RT"}  # poses are in the map view; the graph view shows the symbolic structure


class GraphLogger:
    def __init__(self, recorder: Any, min_period_s: float = 5.0) -> None:
        self.rec = recorder
        self.min_period_s = min_period_s
        self._last_signature: tuple[Any, ...] | None = None
        self._last_time: float | None = None

    def maybe_log(self, graph: Any, now_s: float | None, force: bool = False) -> None:
        if not self.rec.enabled or now_s is None:
            return
        nodes = sorted((n.id, n.type, n.name, str(n.attrs.get("state", ""))) for n in _all_nodes(graph))
        edges = sorted((e.src, e.dst, e.type) for e in _all_edges(graph) if e.type not in HIDDEN_EDGES)
        signature = (tuple(nodes), tuple(edges))
        if not force and signature == self._last_signature:
            return
        if not force and self._last_time is not None and now_s - self._last_time < self.min_period_s:
            return
        import rerun as rr

        self._last_signature, self._last_time = signature, now_s
        ids = [str(n[0]) for n in nodes]
        labels = [f"{n[2]}" + (f" [{n[3]}]" if n[3] else "") for n in nodes]
        colours = [TYPE_COLOURS.get(n[1], (180, 180, 180)) for n in nodes]
        positions = layout(graph, [n[0] for n in nodes])
        self.rec.set_time(now_s)
        self.rec.log("dsr", rr.GraphNodes(ids, labels=labels, colors=colours, positions=positions),
                     rr.GraphEdges([(str(s), str(d)) for s, d, _ in edges], graph_type="directed"))


PX_PER_M = 60.0


def layout(graph: Any, node_ids: list[int]) -> list[tuple[float, float]]:
    """Place the graph like the building: things with a pose where they are (rooms at their
    centre, doors at the door), activities next to their object, the rest (world, clock,
    missions, intentions, requests) in a column to the right, so the view reads like the map."""
    placed: dict[int, tuple[float, float]] = {}
    xmax = 0.0
    for node_id in node_ids:
        node = graph.get_node(node_id)
        xy: tuple[float, float] | None = None
        if node.type == "room" and node.attrs.get("polygon_x"):
            xs, ys = node.attrs["polygon_x"], node.attrs.get("polygon_y", [])
            xy = (sum(xs) / len(xs), sum(ys) / max(len(ys), 1))
        elif node.type == "door" and "x" in node.attrs:
            xy = (float(node.attrs["x"]), float(node.attrs["y"]))
        elif node.type in ("person", "object", "robot"):
            try:
                x, y, _ = graph.world_pose(node_id)
                xy = (x, y)
            except Exception:  # noqa: BLE001 - no pose yet: goes to the column
                xy = None
        if xy is not None:
            placed[node_id] = xy
            xmax = max(xmax, xy[0])
    column = 0
    for node_id in node_ids:
        if node_id in placed:
            continue
        node = graph.get_node(node_id)
        obj = graph.get_node_by_name(str(node.attrs.get("object", ""))) if node.type == "activity" else None
        if obj is not None and obj.id in placed:
            ox, oy = placed[obj.id]
            placed[node_id] = (ox + 0.6, oy + 0.6)
        else:
            placed[node_id] = (xmax + 3.0, column * 0.8)
            column += 1
    return [(placed[i][0] * PX_PER_M, -placed[i][1] * PX_PER_M) for i in node_ids]


def _all_nodes(graph: Any) -> list[Any]:
    return list(graph.nodes())


def _all_edges(graph: Any) -> list[Any]:
    return list(graph.edges())
