"""The executive agent: missions -> plans -> intentions, monitored until done or failed.

The DSR contract (fixed; see docs/ARCHITECTURE.md, names in agents/world/vocabulary.py):
- ``mission/<id>`` nodes (type ``mission``): ``mission_id``, ``goal`` (mission string), ``time_s``,
  ``state`` pending -> active -> done | failed, ``reason``, ``started_s``, ``finished_s``, ``plan``
  (rule names), ``replans``.
- ``intention/<id>/<attempt>.<step>`` nodes (type ``intention``) with an edge intention -(step_of)->
  mission: ``kind`` navigate | wait, ``state`` active -> done | failed (navigate: written by the
  social navigation; wait: by this agent when the activity has ended) | cancelled,
  ``goal_x/goal_y/goal_theta/goal_has_theta`` or ``until_s``, ``rule``, ``bindings``, ``reason``.
The executive writes missions and intentions; social navigation only flips a navigate intention's state.

Replans (why two budgets): a step that fails (no path, timed out) may be retried MAX_REPLANS times;
a world that changes under the plan (the approached person walks on, an agenda change or a door
alters the route) is not a failure, and is followed up to MAX_WORLD_REPLANS times.
"""

from __future__ import annotations

import gc
from collections import Counter

from agents.missions.kinds import MissionStringError
from agents.missions.planning import MissionPlanner, intention_end, remaining_route, route_rooms
from agents.missions.steps import PlanStep, StepFailed
from agents.runtime.base import Agent
from agents.runtime.checked_graph import CheckedGraph
from agents.runtime.recording import Recorder
from agents.world.freshness import interactions_follow_activities, mark_observed, observed_up_to
from agents.world.vocabulary import (ActivityView, ClockView, EdgeType, IntentionKind, IntentionState,
                                     IntentionView, MissionState, MissionView, NodeType, intention_name, intentions,
                                     mission_name, missions)
from dsr.model import Attrs
from scenes.clock import format_clock, parse_clock

MAX_REPLANS = 4
MAX_WORLD_REPLANS = 20
FAILURE, WORLD = "failure", "world"


class ExecutiveAgent(Agent):
    kind = "executive"

    def setup(self, graph: CheckedGraph, recorder: Recorder) -> None:
        self.graph = graph
        self.rec = recorder
        self.planner = MissionPlanner(self.scene, grammar_file=self.config.options.get("grammar"))
        self._steps: dict[str, list[PlanStep]] = {}
        self._replans: dict[str, Counter[str]] = {}
        self._written_missions = False
        self.perception_lockstep = self.config.option("perception_lockstep", "0") == "1"
        self._dirty = True
        self._world_changed = False
        self._seen_version = -1
        self._symbolic: dict[int, Attrs] | None = None   # activities and doors as last seen

    def _look(self) -> None:
        """Has the graph changed since the last step, and have its activities or doors?

        Why the graph's version and not the DSR's change signals: this agent only needs to know
        *that* something changed, but a signal builds and queues a snapshot of the changed node
        for it, and every person's move changes a node ten times a second (hundreds a second of
        snapshots, queued up while the executive plans).  Activities and doors are what the
        grammar's preconditions read: a change to one (added, updated or gone) re-checks the
        plan's route."""
        version = self.graph.version
        if version == self._seen_version:
            return
        self._seen_version = version
        self._dirty = True
        symbolic = {node.id: node.attrs for kind in (NodeType.ACTIVITY, NodeType.DOOR)
                    for node in self.graph.nodes_of_type(kind)}
        if self._symbolic is not None and symbolic != self._symbolic:
            self._world_changed = True
        self._symbolic = symbolic

    def _write_missions(self) -> None:
        """Missions of the day, once (a restarted executive finds them already in the graph)."""
        g = self.graph
        with g.transaction():
            for mission in self.scene.missions:
                if g.get_node_by_name(mission_name(mission.id)) is None:
                    g.insert_node(type=NodeType.MISSION, name=mission_name(mission.id),
                                  attrs={"mission_id": mission.id, "goal": mission.goal_text(),
                                         "time_s": parse_clock(mission.time), "state": MissionState.PENDING,
                                         "description": mission.description, "replans": 0})
        self._written_missions = True

    def step(self) -> None:
        g = self.graph
        clock = ClockView.of(g)
        if clock is None or g.get_node_by_name(self.scene.robot.name) is None:
            return
        if not self._written_missions:
            self._write_missions()
        now_s = clock.now_s
        self.rec.set_time(now_s)
        if self.perception_lockstep:
            # In lockstep (chronav evaluate, in-process runs): act on a tick once the perceivers saw
            # it, and say so, so the navigation and the clock wait for what this agent decides then.
            if not observed_up_to(g, now_s, slack_s=0.0):
                return
            self._react(now_s)
            mark_observed(g, self.config.name, now_s)
            return
        self._react(now_s)

    def _react(self, now_s: float) -> None:
        """Monitor the active mission, or start the first one due (when anything changed)."""
        g = self.graph
        self._look()
        if not self._dirty:
            return
        self._dirty = False
        day = missions(g)
        active = [m for m in day if m.state == MissionState.ACTIVE]
        if active:
            self._monitor(active[0], now_s)
            return
        due = [m for m in day if m.state == MissionState.PENDING and m.time_s <= now_s]
        if due and not (observed_up_to(g, now_s) and interactions_follow_activities(g)):
            self._dirty = True  # after a clock skip or an activity's end: plan on the world of now
            return
        if due:
            self._start(due[0], now_s)

    def _mission(self, mission: MissionView) -> MissionView:
        """The mission as the DSR holds it now (after this agent's own writes)."""
        return MissionView.from_node(self.graph.get_node(mission.node_id))

    # ----------------------------------------------------------------- mission lifecycle
    def _start(self, mission: MissionView, now_s: float) -> None:
        self.graph.update_node(mission.node_id, attrs={"state": MissionState.ACTIVE, "started_s": now_s})
        self.rec.event(f"{format_clock(now_s)} mission {mission.mission_id} ({mission.goal}) started")
        self._replans[mission.mission_id] = Counter()
        self._plan(self._mission(mission), now_s, reason="start")

    def _grammar_plan(self, goal: str) -> list[PlanStep]:
        """The grammar's steps for ``goal`` on the world of now (raises StepFailed, MissionStringError).

        Why a collection after it: a plan builds a networkx copy of the world (whose cached views
        refer back to it) and a matcher whose compiled patterns refer to the matcher: reference
        cycles, which only the cyclic collector frees.  While the executive plans, the replica
        goes on merging deltas; a collection then finds the plan's objects in use and ages them,
        and under a replica's raised thresholds (dsr/collector.py) they waited minutes for the
        next older collection, a few MB of them at a time.  The heap kept each such peak, and
        the executive grew mission after mission in real time.  Collecting the two young
        generations at once costs about a millisecond."""
        try:
            return self.planner.plan(self.graph, goal).steps
        finally:
            gc.collect(1)

    def _plan(self, mission: MissionView, now_s: float, reason: str) -> None:
        try:
            steps = self._grammar_plan(mission.goal)
        except (StepFailed, MissionStringError) as exc:
            self._finish(mission, now_s, MissionState.FAILED, f"no plan: {exc}")
            return
        self._steps[mission.mission_id] = steps
        self._world_changed = False   # planned on the world of now: earlier changes are in the plan
        explained = " -> ".join(step.describe() for step in steps) or "(already satisfied)"
        self.graph.update_node(mission.node_id, attrs={"plan": [s.rule for s in steps]})
        self.rec.event(f"{format_clock(now_s)} plan for {mission.mission_id} ({reason}): {explained}")
        self.log.info("plan for %s (%s): %s", mission.mission_id, reason, explained)
        if not steps:
            self._finish(mission, now_s, MissionState.DONE, "")
            return
        self._issue(mission, steps, 0, now_s)

    def _issue(self, mission: MissionView, steps: list[PlanStep], first: int, now_s: float) -> None:
        g = self.graph
        index = intention_end(steps, first)
        step = steps[index]
        try:
            attrs = step.intention_attrs(g, self.scene)
        except StepFailed as exc:
            self._replan_or_fail(mission, now_s, f"step {step.rule}: {exc}", FAILURE)
            return
        rooms = route_rooms(steps, first, index)
        if rooms:
            attrs["rooms"] = rooms
        name = intention_name(mission.mission_id, mission.replans, index)
        with g.transaction():
            self._cancel_active(mission.mission_id)
            node = g.get_node_by_name(name) or g.insert_node(type=NodeType.INTENTION, name=name, attrs={})
            g.update_node(node.id, attrs={**attrs, "mission_id": mission.mission_id, "step": index, "rule": step.rule,
                                          "bindings": [f"{k}={v}" for k, v in sorted(step.bindings.items())],
                                          "state": IntentionState.ACTIVE, "issued_s": now_s})
            g.insert_or_assign_edge(node.id, mission.node_id, EdgeType.STEP_OF, attrs={})
        merged = " -> ".join(st.describe() for st in steps[first:index + 1])
        which = f"steps {first + 1}-{index + 1}" if index > first else f"step {index + 1}"
        self.rec.event(f"{format_clock(now_s)} {mission.mission_id} {which}/{len(steps)}: {merged}")

    def _forget_intentions(self, mission_id: str) -> None:
        """A finished mission's intentions leave the graph (their ``step_of`` edges with them).

        Why: every replica holds every intention, with its path, and the navigation and the
        simulator scan them all each step; kept, a day of missions grows every agent's memory and
        step time mission after mission.  What they did stays in plans.jsonl and the recording, and
        the mission node keeps its plan, state, times and reason.  An active intention is removed
        the same way: to the navigation a removed intention is a cancelled one."""
        for old in intentions(self.graph, mission_id):
            self.graph.delete_node(old.node_id)

    def _cancel_active(self, mission_id: str) -> None:
        for old in intentions(self.graph, mission_id):
            if old.active:
                self.graph.update_node(old.node_id, attrs={"state": IntentionState.CANCELLED})

    def _monitor(self, mission: MissionView, now_s: float) -> None:
        steps = self._steps.get(mission.mission_id)
        if steps is None:  # restarted executive: plan again from the current world
            self._replans.setdefault(mission.mission_id, Counter())
            self._plan(mission, now_s, reason="executive restarted")
            return
        current_ones = [i for i in intentions(self.graph, mission.mission_id) if i.state != IntentionState.CANCELLED]
        if not current_ones:
            self._issue(mission, steps, 0, now_s)
            return
        current = max(current_ones, key=lambda i: i.issued_s)
        if current.step >= len(steps):
            self._plan(mission, now_s, reason="plan changed under a running step")
            return
        step = steps[current.step]
        if current.active and current.kind == IntentionKind.WAIT:
            self._watch_wait(current, step, now_s)
            current = IntentionView.from_node(self.graph.get_node(current.node_id))
        if current.state == IntentionState.DONE:
            if current.step + 1 < len(steps):
                self._issue(mission, steps, current.step + 1, now_s)
            else:
                self._finish(mission, now_s, MissionState.DONE, "")
        elif current.state == IntentionState.FAILED:
            self._replan_or_fail(mission, now_s, current.reason or "step failed", FAILURE)
        elif current.active and step.diverged(self.graph):
            self._replan_or_fail(mission, now_s, f"world diverged during {step.rule}", WORLD)
        elif current.active and self._world_changed:
            self._world_changed = False
            self._check_route(mission, steps, now_s)

    def _watch_wait(self, intention: IntentionView, step: PlanStep, now_s: float) -> None:
        """A wait is this agent's own intention: done once the activity has ended; its deadline
        follows the activity when the agenda moves it (the simulator skips idle time up to it)."""
        activity: ActivityView | None = step.awaited(self.graph)
        if step.wait_over(self.graph):
            self.graph.update_node(intention.node_id, attrs={"state": IntentionState.DONE})
            ended = "left the agenda" if activity is None else activity.state
            self.rec.event(f"{format_clock(now_s)} waited for {step.subject} ({ended})")
        elif activity is not None and activity.end_s != intention.until_s:
            self.graph.update_node(intention.node_id, attrs={"until_s": activity.end_s})

    def _check_route(self, mission: MissionView, steps: list[PlanStep], now_s: float) -> None:
        """Replan when an agenda change or a door makes the symbolic plan's remaining route differ."""
        g = self.graph
        robot = g.get_node_by_name(self.scene.robot.name)
        here = next((g.get_node(e.dst).name for e in g.edges_from(robot.id, EdgeType.IN) if g.get_node(e.dst)), None)
        try:
            fresh = self._grammar_plan(mission.goal)
        except (StepFailed, MissionStringError) as exc:
            self._replan_or_fail(mission, now_s, f"world diverged: {exc}", WORLD)
            return
        old, new = remaining_route(steps, here), remaining_route(fresh, here)
        if old != new:
            self._replan_or_fail(mission, now_s, f"world diverged: route {' -> '.join(old) or '-'} is now "
                                                 f"{' -> '.join(new) or '-'}", WORLD)

    def _replan_or_fail(self, mission: MissionView, now_s: float, reason: str, cause: str) -> None:
        counts = self._replans.setdefault(mission.mission_id, Counter())
        limit = MAX_REPLANS if cause == FAILURE else MAX_WORLD_REPLANS
        if counts[cause] >= limit:
            self._finish(mission, now_s, MissionState.FAILED, reason)
            return
        counts[cause] += 1
        self.graph.update_node(mission.node_id, attrs={"replans": mission.replans + 1})
        self.rec.event(f"{format_clock(now_s)} replanning {mission.mission_id}: {reason}", level="WARN")
        self._plan(self._mission(mission), now_s, reason=reason)

    def _finish(self, mission: MissionView, now_s: float, state: str, reason: str) -> None:
        g = self.graph
        with g.transaction():
            g.update_node(mission.node_id, attrs={"state": state, "finished_s": now_s, "reason": reason})
            self._forget_intentions(mission.mission_id)
        self._steps.pop(mission.mission_id, None)
        self._replans.pop(mission.mission_id, None)   # a week's missions must not pile up here
        took = now_s - (mission.started_s if mission.started_s is not None else now_s)
        ok = state == MissionState.DONE
        self.rec.event(f"{format_clock(now_s)} mission {mission.mission_id} {state}"
                       f"{': ' + reason if reason else ''} ({took:.0f} s)", level="INFO" if ok else "ERROR")
        self.log.info("mission %s %s %s", mission.mission_id, state, reason)
