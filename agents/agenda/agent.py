"""The agenda agent: the centre's activities in the DSR, each object's R(t), live changes.

Why changes travel through the DSR as ``agenda_request`` nodes (and not a side channel): the
request, who made it and the answer are then part of the replicated, recorded state; the write
policy that guards the graph also guards the agenda (only agenda writers may create requests);
and `chronav agenda` needs nothing but a DSR replica to talk to a running system.

Request protocol: a client inserts ``agenda_request/<uuid>`` (type ``agenda_request``) with
``change`` = JSON of an add / cancel / move / load change (agents/agenda/changes.py) and
``state`` = ``pending``; this agent applies it atomically and sets ``state`` to ``accepted`` or
``refused`` with a ``message`` a person can act on. Refused changes leave the agenda untouched.
"""

from __future__ import annotations

from agents.lib.agenda.changes import AgendaChangeError, apply_change, parse_change
from agents.lib.agenda.chronemics import UPCOMING_WINDOW_S, ChronemicsParams
from agents.lib.agenda.model import AgendaDay
from agents.runtime.base import Agent
from agents.runtime.checked_graph import CheckedGraph
from agents.runtime.drawing.series import log_series_styles
from agents.runtime.recording import FramePacer, Recorder
from agents.world.dsr_writers import agenda_log, write_activities, write_object_r
from agents.world.freshness import mark_observed
from agents.world.vocabulary import ClockView, NodeType, RequestState
from dsr.attr_values import as_strs
from dsr.model import Attrs
from scenes.clock import format_clock


#: R(t) is drawn at most this often (sim s): it moves over minutes, and the agent loops at 50 Hz
R_DRAW_EVERY_S = 1.0


class AgendaAgent(Agent):
    kind = "agenda"

    def setup(self, graph: CheckedGraph, recorder: Recorder) -> None:
        self.graph = graph
        self.rec = recorder
        self.params = ChronemicsParams()
        self.day = self.world.agenda  # validated when the scene was loaded (agents/world/scene_world.py)
        self._restore_runtime_changes()
        self._complete = False
        self._published: AgendaDay | None = None
        self._r_frames = FramePacer(R_DRAW_EVERY_S)
        log_series_styles(recorder, "metrics/objects", sorted(self.world.object_names))

    # ----------------------------------------------------------------- restart safety
    def _restore_runtime_changes(self) -> None:
        """Replay the accepted changes recorded in the DSR (a restarted agent keeps staff edits)."""
        node = agenda_log(self.graph)
        for text in as_strs(node.attrs.get("changes", [])):
            try:
                self.day = apply_change(self.day, parse_change(text), known_objects=self.world.object_names,
                                        known_rooms=self.world.room_names,
                                        known_people=self.world.person_names)
            except AgendaChangeError as exc:
                self.log.warning("could not replay a recorded change: %s", exc)

    def _remember(self, change_json: str, scripted_key: str | None = None) -> None:
        node = agenda_log(self.graph)
        attrs: Attrs = {"changes": [*as_strs(node.attrs.get("changes", [])), change_json]}
        if scripted_key is not None:
            attrs["applied"] = [*as_strs(node.attrs.get("applied", [])), scripted_key]
        self.graph.update_node(node.id, attrs=attrs)

    # ----------------------------------------------------------------- loop
    def step(self) -> None:
        g = self.graph
        clock = ClockView.of(g)
        if clock is None:
            return
        now_s = clock.now_s
        self.rec.set_time(now_s)
        self._scripted_changes(now_s)
        self._requests(now_s)
        self._publish_activities(now_s)
        self._publish_r(now_s)
        mark_observed(g, self.config.name, now_s)

    def _apply(self, change_json: str, now_s: float, origin: str) -> tuple[bool, str]:
        try:
            change = parse_change(change_json)
            new_day = apply_change(self.day, change, known_objects=self.world.object_names,
                                   known_rooms=self.world.room_names, known_people=self.world.person_names)
        except AgendaChangeError as exc:
            reason = str(exc).removeprefix("refused: ")     # the change's errors say "refused: " already
            self.rec.event(f"{format_clock(now_s)} agenda change from {origin} refused: {reason}", level="WARN")
            return False, str(exc)
        before = {a.id: a for a in self.day.activities}
        self.day = new_day
        changed = [a for a in new_day.activities if before.get(a.id) != a]
        removed = sorted(set(before) - {a.id for a in new_day.activities})
        summary = ", ".join(f"{a.id} {a.object} {format_clock(a.start_s)}-{format_clock(a.end_s)} "
                            f"{a.at(now_s, UPCOMING_WINDOW_S).state.value}"
                            for a in changed) or "no change"
        if removed:
            summary += f"; removed {', '.join(removed)}"
        message = f"{change.op}: {summary}"
        self.rec.event(f"{format_clock(now_s)} agenda change from {origin} accepted: {message}")
        self.log.info("agenda change from %s accepted: %s", origin, message)
        return True, message

    def _scripted_changes(self, now_s: float) -> None:
        """Scene ``agenda_changes``: staff edits scripted at a sim time (applied once, restart-safe),
        in the order agents/world/timeline.py applies them offline."""
        applied = set(as_strs(agenda_log(self.graph).attrs.get("applied", [])))
        for change in self.world.scripted:
            if change.key in applied or change.at_s > now_s:
                continue
            ok, _ = self._apply(change.text, now_s, origin=f"scene agenda_changes[{change.index}]")
            if ok:
                self._remember(change.text, scripted_key=change.key)
            else:
                self._remember_skip(change.key)

    def _remember_skip(self, key: str) -> None:
        node = agenda_log(self.graph)
        self.graph.update_node(node.id, attrs={"applied": [*as_strs(node.attrs.get("applied", [])), key]})

    def _requests(self, now_s: float) -> None:
        for request in self.graph.nodes_of_type(NodeType.AGENDA_REQUEST):
            if request.attrs.get("state") != RequestState.PENDING:
                continue
            text = request.attrs.get("change")
            if not isinstance(text, str):
                ok, message = False, "refused: request has no 'change' attribute (JSON text)"
            else:
                ok, message = self._apply(text, now_s, origin=str(request.attrs.get("requested_by", request.name)))
            # One delta: a change is never in the log without its answer, or answered without being
            # logged (a kill in between made a restarted agent apply it twice).
            with self.graph.transaction():
                if ok:
                    self._remember(str(text))
                if self.graph.get_node(request.id) is not None:  # the requester may have withdrawn it
                    self.graph.update_node(request.id, attrs={"state": RequestState.ACCEPTED if ok else RequestState.REFUSED,
                                                              "message": message, "answered_s": now_s})

    def _publish_activities(self, now_s: float) -> None:
        day_now = self.day.at(now_s, UPCOMING_WINDOW_S)
        if day_now == self._published and self._complete:
            return
        # Edges to objects/people not yet in the graph are written on a later call.
        self._complete = write_activities(self.graph, day_now)
        self._published = day_now

    def _publish_r(self, now_s: float) -> None:
        values = write_object_r(self.graph, self.day, now_s, self.params)
        if self.rec.enabled and self._r_frames.due(now_s):
            for name, r in values.items():
                self.rec.scalar(f"metrics/objects/{name}", r)
