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
        self.rec.set_time(now_s)
        self.rec.log("dsr", rr.GraphNodes(ids, labels=labels, colors=colours),
                     rr.GraphEdges([(str(s), str(d)) for s, d, _ in edges], graph_type="directed"))


def _all_nodes(graph: Any) -> list[Any]:
    return list(graph.nodes())


def _all_edges(graph: Any) -> list[Any]:
    return list(graph.edges())
