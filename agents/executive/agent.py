"""The executive agent: missions -> plans -> intentions, monitored until done or failed.

The DSR contract (fixed; see docs/ARCHITECTURE.md):
- ``mission/<id>`` nodes (type ``mission``): ``mission_id``, ``goal`` (mission string), ``time_s``,
  ``state`` pending -> active -> done | failed, ``reason``, ``started_s``, ``finished_s``, ``plan``
  (rule names), ``replans``.
- ``intention/<id>/<k>`` nodes (type ``intention``) with an edge intention -(step_of)-> mission:
  ``kind`` navigate | wait, ``state`` active -> done | failed (written by the executing agent),
  ``goal_x/goal_y/goal_theta/goal_has_theta`` or ``until_s``, ``rule``, ``bindings``, ``reason``.
The executive writes missions and intentions; social navigation only flips an intention's state.
"""

from __future__ import annotations

from agents.missions.planning import MissionPlanner, PlanStep, StepFailed
from agents.runtime.base import Agent
from agents.runtime.recording import Recorder
from scenes.clock import format_clock, parse_clock

MAX_REPLANS = 4


class ExecutiveAgent(Agent):
    kind = "executive"

    def setup(self, graph, recorder: Recorder) -> None:  # noqa: ANN001
        self.graph = graph
        self.rec = recorder
        self.planner = MissionPlanner(self.scene, grammar_file=self.config.options.get("grammar"))
        self._steps: dict[str, list[PlanStep]] = {}
        self._written_missions = False
        self._dirty = True
        self._world_changed = False
        for signal in ("node_added", "node_updated", "node_deleted", "edge_added", "edge_deleted"):
            graph.connect(signal, self._on_change)
        graph.connect("node_added", self._on_symbolic_change)
        graph.connect("node_updated", self._on_symbolic_change)

    def _on_change(self, *_args: object) -> None:
        self._dirty = True

    def _on_symbolic_change(self, node, *_rest: object) -> None:  # noqa: ANN001 - dsr.Node
        """Activities and doors are what the grammar's preconditions read: re-check the plan."""
        if node.type in ("activity", "door"):
            self._world_changed = True

    def _write_missions(self) -> None:
        """Missions of the day, once (a restarted executive finds them already in the graph)."""
        g = self.graph
        with g.transaction():
            for mission in self.scene.missions:
                if g.get_node_by_name(f"mission/{mission.id}") is None:
                    g.insert_node(type="mission", name=f"mission/{mission.id}",
                                  attrs={"mission_id": mission.id, "goal": mission.goal_text(),
                                         "time_s": parse_clock(mission.time), "state": "pending",
                                         "description": mission.description, "replans": 0})
        self._written_missions = True

    def step(self) -> None:
        g = self.graph
        clock = g.get_node_by_name("clock")
        if clock is None or g.get_node_by_name(self.scene.robot.name) is None:
            return
        if not self._written_missions:
            self._write_missions()
        now_s = float(clock.attrs["now_s"])
        self.rec.set_time(now_s)
        if not self._dirty:
            return
        self._dirty = False
        missions = sorted(g.nodes_of_type("mission"), key=lambda n: float(n.attrs.get("time_s", 0)))
        active = [m for m in missions if m.attrs.get("state") == "active"]
        if active:
            self._monitor(active[0], now_s)
            return
        due = [m for m in missions if m.attrs.get("state") == "pending" and float(m.attrs["time_s"]) <= now_s]
        if due:
            self._start(due[0], now_s)

    # ----------------------------------------------------------------- mission lifecycle
    def _start(self, mission, now_s: float) -> None:  # noqa: ANN001
        self.graph.update_node(mission.id, attrs={"state": "active", "started_s": now_s})
        self.rec.event(f"{format_clock(now_s)} mission {mission.attrs['mission_id']} ({mission.attrs['goal']}) started")
        self._plan(mission, now_s, reason="start")

    def _plan(self, mission, now_s: float, reason: str) -> None:  # noqa: ANN001
        mission_id = str(mission.attrs["mission_id"])
        try:
            steps = self.planner.plan(self.graph, str(mission.attrs["goal"]), now_s)
        except StepFailed as exc:
            self._finish(mission, now_s, "failed", f"no plan: {exc}")
            return
        self._steps[mission_id] = steps
        explained = " -> ".join(step.describe() for step in steps) or "(already satisfied)"
        self.graph.update_node(mission.id, attrs={"plan": [s.rule for s in steps]})
        self.rec.event(f"{format_clock(now_s)} plan for {mission_id} ({reason}): {explained}")
        self.log.info("plan for %s (%s): %s", mission_id, reason, explained)
        if not steps:
            self._finish(mission, now_s, "done", "")
            return
        self._issue(mission, steps, 0, now_s)

    def _issue(self, mission, steps: list[PlanStep], index: int, now_s: float) -> None:  # noqa: ANN001
        g = self.graph
        mission_id = str(mission.attrs["mission_id"])
        first = index
        while index + 1 < len(steps) and steps[index].rule == "changeRoom" and steps[index + 1].navigates:
            index += 1  # door-to-door hops followed by a move: one intention, confined to the route's rooms
        step = steps[index]
        try:
            attrs = step.intention_attrs(g, now_s)
        except StepFailed as exc:
            self._replan_or_fail(mission, now_s, f"step {step.rule}: {exc}")
            return
        if index > first:
            hops = steps[first:index]
            attrs["rooms"] = [hops[0].bindings["r1"], *(hop.bindings["r2"] for hop in hops),
                              *([step.bindings["room"]] if step.rule == "goToRoom" else [])]
            attrs["pass_through"] = step.rule == "changeRoom"
        replans = int(mission.attrs.get("replans", 0))
        name = f"intention/{mission_id}/{replans}.{index}"
        with g.transaction():
            for old in g.nodes_of_type("intention"):
                if old.attrs.get("mission_id") == mission_id and old.attrs.get("state") == "active":
                    g.update_node(old.id, attrs={"state": "cancelled"})
            node = g.get_node_by_name(name) or g.insert_node(type="intention", name=name, attrs={})
            g.update_node(node.id, attrs={**attrs, "mission_id": mission_id, "step": index, "rule": step.rule,
                                          "bindings": [f"{k}={v}" for k, v in sorted(step.bindings.items())],
                                          "state": "active", "issued_s": now_s})
            g.insert_or_assign_edge(node.id, mission.id, "step_of", attrs={})
        merged = " -> ".join(st.describe() for st in steps[first:index + 1])
        self.rec.event(f"{format_clock(now_s)} {mission_id} steps {first + 1}-{index + 1}/{len(steps)}: {merged}"
                       if index > first else f"{format_clock(now_s)} {mission_id} step {index + 1}/{len(steps)}: "
                       f"{step.describe()}")

    def _monitor(self, mission, now_s: float) -> None:  # noqa: ANN001
        g = self.graph
        mission_id = str(mission.attrs["mission_id"])
        steps = self._steps.get(mission_id)
        if steps is None:  # restarted executive: plan again from the current world
            self._plan(mission, now_s, reason="executive restarted")
            return
        intentions = [n for n in g.nodes_of_type("intention")
                      if n.attrs.get("mission_id") == mission_id and n.attrs.get("state") != "cancelled"]
        if not intentions:
            self._issue(mission, steps, 0, now_s)
            return
        current = max(intentions, key=lambda n: float(n.attrs.get("issued_s", 0)))
        state = current.attrs.get("state")
        index = int(current.attrs.get("step", 0))
        if state == "done":
            if index + 1 < len(steps):
                self._issue(mission, steps, index + 1, now_s)
            else:
                self._finish(mission, now_s, "done", "")
        elif state == "failed":
            self._replan_or_fail(mission, now_s, str(current.attrs.get("reason", "step failed")))
        elif state == "active" and steps[index].diverged(g, now_s):
            self._replan_or_fail(mission, now_s, f"world diverged during {steps[index].rule}")
        elif state == "active" and self._world_changed:
            self._world_changed = False
            self._check_route(mission, steps, now_s)

    def _check_route(self, mission, steps: list[PlanStep], now_s: float) -> None:  # noqa: ANN001
        """Replan when an agenda change or a door makes the symbolic plan's remaining route differ."""
        g = self.graph
        robot = g.get_node_by_name(self.scene.robot.name)
        here = next((g.get_node(e.dst).name for e in g.edges_from(robot.id, "in") if g.get_node(e.dst)), None)
        try:
            fresh = self.planner.plan(g, str(mission.attrs["goal"]), now_s)
        except StepFailed as exc:
            self._replan_or_fail(mission, now_s, f"world diverged: {exc}")
            return
        if _route(steps, here) != _route(fresh, here):
            old, new = " -> ".join(_route(steps, here)) or "-", " -> ".join(_route(fresh, here)) or "-"
            self._replan_or_fail(mission, now_s, f"world diverged: route {old} is now {new}")

    def _replan_or_fail(self, mission, now_s: float, reason: str) -> None:  # noqa: ANN001
        replans = int(mission.attrs.get("replans", 0))
        if replans >= MAX_REPLANS:
            self._finish(mission, now_s, "failed", reason)
            return
        self.graph.update_node(mission.id, attrs={"replans": replans + 1})
        self.rec.event(f"{format_clock(now_s)} replanning {mission.attrs['mission_id']}: {reason}", level="WARN")
        self._plan(self.graph.get_node(mission.id), now_s, reason=reason)

    def _finish(self, mission, now_s: float, state: str, reason: str) -> None:  # noqa: ANN001
        g = self.graph
        with g.transaction():
            g.update_node(mission.id, attrs={"state": state, "finished_s": now_s, "reason": reason})
            for node in g.nodes_of_type("intention"):
                if node.attrs.get("mission_id") == mission.attrs["mission_id"] and node.attrs.get("state") == "active":
                    g.update_node(node.id, attrs={"state": "cancelled"})
        took = now_s - float(mission.attrs.get("started_s", now_s))
        self.rec.event(f"{format_clock(now_s)} mission {mission.attrs['mission_id']} {state}"
                       f"{': ' + reason if reason else ''} ({took:.0f} s)", level="INFO" if state == "done" else "ERROR")
        self.log.info("mission %s %s %s", mission.attrs["mission_id"], state, reason)


def _route(steps: list[PlanStep], here: str | None) -> list[str]:
    """The rooms still to enter (and waits still to do), from the robot's current room on."""
    route = [step.bindings["r2"] if step.rule == "changeRoom" else f"wait:{step.bindings.get('a', '')}"
             for step in steps if step.rule in ("changeRoom", "waitForPassage")]
    if here in route:
        route = route[route.index(here) + 1:]
    return route
