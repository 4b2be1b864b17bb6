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

import json

from agents.agenda.changes import AgendaChangeError, apply_change, parse_change
from agents.agenda.expand import expand_day
from agents.agenda.model import Activity, AgendaDay, AgendaError, format_clock
from agents.agenda.yaml_source import load_scene_agenda
from agents.runtime.base import Agent
from agents.runtime.freshness import mark_observed
from agents.runtime.recording import Recorder
from agents.social_navigation.chronemics import ChronemicsParams, r_band, r_of_t

R_EPSILON = 1e-3


class AgendaAgent(Agent):
    kind = "agenda"

    def setup(self, graph, recorder: Recorder) -> None:  # noqa: ANN001
        self.graph = graph
        self.rec = recorder
        self.params = ChronemicsParams()
        self.upcoming_window_s = self.params.ramp_before_s  # "upcoming" = R(t) already rising
        clock = self.scene.clock
        self.objects = {o.name for o in self.scene.objects}
        self.rooms = {r.name for r in self.scene.rooms}
        try:
            sources = load_scene_agenda(self.config.scene)
            self.day = expand_day(sources, clock.date, clock.timezone, self.objects, known_rooms=self.rooms)
        except AgendaError as exc:
            # A broken agenda must not take the robot down: run with an empty day, say why loudly.
            self.log.error("agenda of %s could not be loaded, starting empty:\n%s", self.config.scene, exc)
            self.rec.event(f"agenda not loaded: {exc}", level="ERROR")
            self.day = AgendaDay(date=clock.date, tz=clock.timezone)
        self._restore_runtime_changes()
        self._published: dict[str, dict[str, object]] = {}
        self._dirty = True

    # ----------------------------------------------------------------- restart safety
    def _agenda_node(self):  # noqa: ANN202
        g = self.graph
        node = g.get_node_by_name("agenda")
        if node is None:
            node = g.insert_node(type="agenda", name="agenda", attrs={"applied": [], "changes": []})
        return node

    def _restore_runtime_changes(self) -> None:
        """Replay the accepted changes recorded in the DSR (a restarted agent keeps staff edits)."""
        node = self._agenda_node()
        for text in node.attrs.get("changes", []):
            try:
                self.day = apply_change(self.day, parse_change(text), known_objects=self.objects,
                                        known_rooms=self.rooms)
            except AgendaChangeError as exc:
                self.log.warning("could not replay a recorded change: %s", exc)

    def _remember(self, change_json: str, scripted_key: str | None = None) -> None:
        node = self._agenda_node()
        attrs: dict[str, object] = {"changes": [*node.attrs.get("changes", []), change_json]}
        if scripted_key is not None:
            attrs["applied"] = [*node.attrs.get("applied", []), scripted_key]
        self.graph.update_node(node.id, attrs=attrs)

    # ----------------------------------------------------------------- loop
    def step(self) -> None:
        g = self.graph
        clock = g.get_node_by_name("clock")
        if clock is None:
            return
        now_s = float(clock.attrs["now_s"])
        self.rec.set_time(now_s)
        self._scripted_changes(now_s)
        self._requests(now_s)
        self._publish_activities(now_s)
        self._publish_r(now_s)
        mark_observed(g, self.config.name, now_s)

    def _apply(self, change_json: str, now_s: float, origin: str) -> tuple[bool, str]:
        try:
            change = parse_change(change_json)
            new_day = apply_change(self.day, change, known_objects=self.objects, known_rooms=self.rooms)
        except AgendaChangeError as exc:
            self.rec.event(f"{format_clock(now_s)} agenda change from {origin} refused: {exc}", level="WARN")
            return False, str(exc)
        before = {a.id: a for a in self.day.activities}
        self.day = new_day
        changed = [a for a in new_day.activities if before.get(a.id) != a]
        removed = sorted(set(before) - {a.id for a in new_day.activities})
        summary = ", ".join(f"{a.id} {a.object} {format_clock(a.start_s)}-{format_clock(a.end_s)} "
                            f"{a.at(now_s, self.upcoming_window_s).state.value}"
                            for a in changed) or "no change"
        if removed:
            summary += f"; removed {', '.join(removed)}"
        message = f"{change.op}: {summary}"
        self.rec.event(f"{format_clock(now_s)} agenda change from {origin} accepted: {message}")
        self.log.info("agenda change from %s accepted: %s", origin, message)
        return True, message

    def _scripted_changes(self, now_s: float) -> None:
        """Scene ``agenda_changes``: staff edits scripted at a sim time (applied once, restart-safe)."""
        from agents.agenda.model import parse_clock

        applied = set(self._agenda_node().attrs.get("applied", []))
        for index, change in enumerate(self.scene.agenda_changes):
            key = f"scene#{index}"
            if key in applied or parse_clock(change.at) > now_s:
                continue
            payload = {k: v for k, v in change.model_dump().items() if k != "at" and v is not None}
            text = json.dumps(payload)
            ok, _ = self._apply(text, now_s, origin=f"scene agenda_changes[{index}]")
            if ok:
                self._remember(text, scripted_key=key)
            else:
                self._remember_skip(key)

    def _remember_skip(self, key: str) -> None:
        node = self._agenda_node()
        self.graph.update_node(node.id, attrs={"applied": [*node.attrs.get("applied", []), key]})

    def _requests(self, now_s: float) -> None:
        for request in self.graph.nodes_of_type("agenda_request"):
            if request.attrs.get("state") != "pending":
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
                    self.graph.update_node(request.id, attrs={"state": "accepted" if ok else "refused",
                                                              "message": message, "answered_s": now_s})

    def _activity_attrs(self, activity: Activity, now_s: float) -> dict[str, object]:
        current = activity.at(now_s, self.upcoming_window_s)
        return {"activity_id": activity.id, "name": activity.name, "object": activity.object,
                "room": activity.room or "", "start_s": activity.start_s, "end_s": activity.end_s,
                "participants": list(activity.participants), "state": current.state.value,
                "source": activity.source}

    def _publish_activities(self, now_s: float) -> None:
        g = self.graph
        wanted = {a.id: self._activity_attrs(a, now_s) for a in self.day.activities}
        if wanted == self._published and not self._dirty:
            return
        with g.transaction():
            for activity_id, attrs in wanted.items():
                name = f"activity/{activity_id}"
                node = g.get_node_by_name(name)
                if node is None:
                    node = g.insert_node(type="activity", name=name, attrs=attrs)
                elif self._published.get(activity_id) != attrs:
                    g.update_node(node.id, attrs=attrs)
                obj = g.get_node_by_name(str(attrs["object"]))
                if obj is not None:
                    g.insert_or_assign_edge(node.id, obj.id, "has", attrs={})
                for person_name in attrs["participants"]:  # type: ignore[union-attr]
                    person = g.get_node_by_name(str(person_name))
                    if person is not None and person.type == "person":
                        g.insert_or_assign_edge(person.id, node.id, "participant", attrs={})
            for node in g.nodes_of_type("activity"):
                if str(node.attrs.get("activity_id")) not in wanted:
                    g.delete_node(node.id)
        # Edges to objects/people that were not yet in the graph: try again next time.
        self._dirty = any(g.get_node_by_name(str(a["object"])) is None for a in wanted.values())
        self._published = wanted

    def _publish_r(self, now_s: float) -> None:
        g = self.graph
        windows = self.day.windows()
        with g.transaction():
            for node in g.nodes_of_type("object"):
                own = [w for w in windows if w.object == node.name]
                r = r_of_t(now_s, own, self.params)
                running = any(w.start_s <= now_s < w.end_s and not w.cancelled for w in own)
                if abs(float(node.attrs.get("R", -1.0)) - r) > R_EPSILON or node.attrs.get("active") != running:
                    g.update_node(node.id, attrs={"R": r, "R_band": r_band(r, self.params), "active": running})
                self.rec.scalar(f"metrics/objects/{node.name}", r)
