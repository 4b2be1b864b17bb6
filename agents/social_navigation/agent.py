"""The social navigation agent: social map -> global path -> local controller -> velocity commands.

The global planner (``-o planner=NAME``) and the local controller (``-o controller=NAME``: chronav's
elastic band by default, navground's behaviours or a plug-in's) are chosen by name through the
registry (agents/lib/registry.py).  A plug-in that raises, answers NaN or infinite commands or a
path off the map is refused: the robot gets a zero command and the mission fails naming it.

It executes ``navigate`` intentions written by the executive.  Why lockstep with the simulator:
it answers every published pose (``pose_stamp``) with one command (``cmd_stamp``), so control runs
at a fixed 0.1 s of sim time whatever the speed-up, and a slow replan simply pauses sim time
instead of letting the robot drive blind.

Replanning (why not adopt on every change): people jitter and R(t) creeps every second.  The map
is rebuilt and searched every ``REPLAN_PERIOD_S`` of sim time (5 Hz, so that moving people are
seen); a new global path is adopted when the current one is blocked (intimate zone, forbidden
space, a body) or costs at least ``REPLAN_GAIN`` more than the new one on the current map.  Every
adoption is logged to the recording.

Why replanning does not stall control: each step first answers the pending pose (the simulator
can integrate the next 0.1 s while this agent plans), and the search reuses the previous ones
through a ``Replanner`` (agents/lib/planning/replan.py: same optimal path, a fraction of the
work when the map changed locally); a new goal or a far-reaching change makes it search afresh.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from agents.runtime.base import Agent
from agents.runtime.checked_graph import CheckedGraph
from agents.world.freshness import LOCKSTEP, observed_s, observed_up_to
from agents.runtime.recording import Recorder
from agents.lib.control import controllers
from agents.lib.control.protocol import ControlInput, LocalController, RobotLimits
from agents.lib.registry import RefusedExtension, UnknownExtension
from agents.lib.socialmap.grid import blocked_core
from agents.lib.planning.paths import densify, nearest_free, nearest_free_where, path_cost
from agents.lib.planning import replan
from agents.lib.socialmap import arrival, banded
from agents.lib.planning.replan import Replanner
from agents.lib.planning.search import GoalOccupied, PlanningError, StartOccupied
from agents.lib.socialmap.social_map import SocialMap
from agents.lib.planning.plan import PlannerFailed, plan
from agents.lib.planning.planners import planner as planner_by_name
from agents.runtime.drawing.social_map import DecisionLogger, DecisionStamp
from agents.world.control_view import obstacle_segments, tracked_people
from agents.world.dsr_readers import closed_doors
from agents.world.navigation import DEFAULT_PLANNER, PLANNING_MARGIN_M, NavigationMaps
from agents.world.plans_file import PlansWriter
from agents.world.vocabulary import IntentionKind, IntentionState, IntentionView, RobotView, intentions
from agents.world.vocabulary import now_s as now_of
from scenes.clock import format_clock
from scenes.angles import wrap_angle

REPLAN_PERIOD_S = 0.2   # sim seconds between map rebuilds and searches (>= 5 Hz, issue 15)
TIME_EPS_S = 1e-6       # sim-time comparisons tolerate float rounding
SLOW_ZONE_M = 0.5
STALL_S = 4.0           # sim seconds without getting closer to the goal before recovering
PROGRESS_M = 0.05
GOAL_TOLERANCE_M = 0.5  # a goal on a blocked cell may move this far to the nearest free cell
ESCAPE_SKIP_M = 0.5     # blocked-path checks ignore the first half metre (the robot's own cell)
CONTACT_M = 0.04        # free space ahead below which the robot backs off instead of pushing
BACK_OFF_MPS = 0.08       # within this much free space ahead (beyond the body) the robot slows down
REPLAN_GAIN = 1.15
PASS_THROUGH_TOLERANCE_M = 0.5   # a waypoint past a door is reached without stopping on it
REPLAN_MIN_GAIN = 0.5   # cost units (~metres of free space): ignore tiny gains near the goal
STALL_TIMEOUT_S = 60.0
BLOCKED_WAIT_S = 30.0   # sim seconds an intention waits for people to clear a blocked way before failing
STAND_IN_AFTER_S = 10.0  # sim seconds a goal occupied by people is waited for before a stand-in is taken
STAND_IN_MAX_M = 1.5     # how far from an occupied goal the stand-in may be (in the goal's room)


def stand_in_goal(grid: np.ndarray, spec: Any, xy: tuple[float, float], inside: Any,
                  max_m: float = STAND_IN_MAX_M) -> tuple[float, float] | None:
    """Where to stop when people stand on the goal: the nearest traversable cell within
    ``max_m`` inside the goal's room (``inside``), or None.  Why: people may stand and talk on
    a mission's goal for minutes; a care robot then stops next to them, outside their intimate
    zones, instead of giving the mission up (the nearest free cell alone could be behind a wall)."""
    return nearest_free_where(grid, spec, xy, max_m, inside)


class SocialNavigationAgent(Agent):
    kind = "social_navigation"

    def setup(self, graph: CheckedGraph, recorder: Recorder) -> None:
        self.graph = graph
        self.rec = recorder
        robot = self.scene.robot
        # Plan with a clearance margin beyond the body: the controller cuts corners a little.
        margin = float(self.config.option("clearance_margin", str(PLANNING_MARGIN_M)))
        # The run's planner (-o planner=NAME, agents/lib/planning/planners.py): plan() and the maps use it.
        self.maps = NavigationMaps.for_scene(self.scene, margin, self.config.option("planner", DEFAULT_PLANNER))
        self.planner = planner_by_name(self.maps.planner)
        self.refusals = 0   # plug-in answers refused (raised, NaN or infinite, a path off the map)
        self.limits = RobotLimits(radius_m=robot.radius, max_speed_mps=robot.max_speed,
                                  max_angular_speed_radps=robot.max_angular_speed,
                                  max_accel_mps2=robot.max_acceleration,
                                  drive="omni" if robot.kinematics == "omnidirectional" else "differential")
        # The run's local controller (-o controller=NAME, agents/lib/control/controllers.py); the
        # launcher checked the name, so a refusal here is a plug-in broken since: the error says so.
        self.controller_name = self.config.option("controller", controllers.DEFAULT_CONTROLLER)
        self.controller: LocalController | None = None
        self.controller_error = ""
        try:
            self.controller = controllers.controller(self.controller_name, self.limits)
        except (RefusedExtension, UnknownExtension) as exc:   # every mission fails naming it; the rest runs
            self.controller_error = str(exc)
            self.log.error("%s", exc)
        wall_hook = getattr(self.controller, "use_wall_check", None)
        if callable(wall_hook):   # a controller that wants the map's word on its band (the elastic band)
            wall_hook(self._cuts_walls)
        self.last_cmd = (0.0, 0.0, 0.0)   # the command last written (the controller's velocity input)
        self._segments: tuple[tuple[str, ...], np.ndarray] | None = None
        self.cruise = self.maps.cruise_speed_mps
        self.control_dt = float(self.config.option("control_dt", "0.1"))
        # -o perception_lockstep=1 (chronav evaluate, in-process runs): answer a pose only once the
        # perceivers and the executive have processed its time, so plans read the people (and the
        # intention) of that very tick.
        self.perception_lockstep = self.config.option("perception_lockstep", "0") == "1"
        self.intention_id: int | None = None
        self.following = False   # a path is adopted and the controller follows it
        self.blocked_since: float | None = None   # sim time since when no path exists (people in the way)
        self.global_points = np.empty((0, 2))
        self._best_distance, self._progress_s = math.inf, 0.0
        self.goal: tuple[float, float, float | None] | None = None
        #: the intention's own goal (self.goal may become a stand-in next to it)
        self.asked_goal: tuple[float, float, float | None] | None = None
        self.last_answered = -1.0
        self.last_replan_s = -math.inf
        self.started_s = 0.0
        #: the longest path adopted for the intention (m): its time budget is
        #: STALL_TIMEOUT_S + 4 x this at cruise speed (the band itself shrinks as the robot advances)
        self.budget_m = 0.0
        self.map: SocialMap | None = None
        self._wall_core: tuple[np.ndarray, np.ndarray] | None = None   # (static grid, blocked_core of it)
        self.replanner = Replanner()   # reuses earlier searches to the same goal (and their buffers)
        replan.warm_up()               # numba: load (or compile) the kernels now, not on the first plan
        arrival.warm_up()
        banded.warm_up()               # the prediction patches of walkers (compiled banding)
        self.route_rooms: tuple[str, ...] = ()
        # The recording's decision layer: every map built is logged at its time (what was used).
        self.decision = DecisionLogger(recorder)
        self._planned_s: float | None = None   # when the path in use was planned (None: no path)
        self.plans = PlansWriter(self.config.run_dir)   # <run>/plans.jsonl: every adopted path
        xmin, _ymin, _xmax, ymax = self.scene.bounds
        self._stamp_anchor = (xmin, ymax + 0.5)

    # ----------------------------------------------------------------- helpers
    def _robot(self) -> Any:
        return self.graph.get_node_by_name(self.scene.robot.name)

    def _build_map(self, now_s: float) -> SocialMap:
        """The social map, confined to the intention's ``rooms`` when the executive's symbolic plan
        fixed the route's rooms (agents/world/navigation.py).  Logged to the recording as built:
        the decision layer shows every map the navigation searched, at its time."""
        smap = self.maps.build(self.graph, now_s, self.route_rooms)
        self.decision.log_map(smap, self._stamp(smap.t_s), self._stamp_anchor)
        return smap

    def _stamp(self, map_s: float) -> DecisionStamp:
        return DecisionStamp(map_s=map_s, planned_s=self._planned_s if self.following else None,
                             seen_s=observed_s(self.graph, "human_observer"))

    def _active_intention(self) -> IntentionView | None:
        """The navigate intention to carry out (one at a time: the executive cancels the previous)."""
        return next((i for i in intentions(self.graph)
                     if i.active and i.kind == IntentionKind.NAVIGATE and i.goal is not None), None)

    def _laser_points(self, robot: Any, pose: tuple[float, float, float]) -> np.ndarray:
        view = RobotView.from_node(robot)
        ranges, angles = np.asarray(view.laser_ranges, dtype=float), np.asarray(view.laser_angles, dtype=float)
        if len(ranges) == 0 or len(ranges) != len(angles):
            return np.empty((0, 2))
        hit = ranges < self.scene.robot.laser_range - 1e-6  # a ray at max range hit nothing
        x, y, theta = pose
        a = angles[hit] + theta
        return np.stack([x + ranges[hit] * np.cos(a), y + ranges[hit] * np.sin(a)], axis=1)

    # ----------------------------------------------------------------- loop
    def step(self) -> None:
        now_s = now_of(self.graph)
        robot = self._robot()
        if now_s is None or robot is None:
            return
        if self.perception_lockstep and not observed_up_to(self.graph, now_s, LOCKSTEP, slack_s=0.0):
            return
        self.rec.set_time(now_s)
        intention = self._active_intention()
        if intention is None:
            if self.intention_id is not None or RobotView.from_node(robot).nav_active:
                self._stop(robot, None, None)
            self.decision.clear()
            return
        if intention.node_id != self.intention_id:
            if observed_up_to(self.graph, now_s):  # after a clock skip, plan on today's people
                self._start(intention, robot, now_s)
            return
        # Answer the pose first: the simulator integrates the next step while this agent replans.
        # In lockstep the replan comes first: once answered, the simulator and the observer move on,
        # and a replan after the answer would read the next tick's pose and people, or not, as the
        # processes' timing decides (a run would not repeat itself).
        pose_stamp = RobotView.from_node(robot).pose_stamp
        if self.perception_lockstep and self._replan_due(intention, now_s):
            if not self.following:
                self._plan(self.graph.world_pose(robot.id), now_s, reason="the way cleared")
            else:
                self._replan(intention, robot, now_s)
        if not self.following:   # people block the way: stand still and try again (_wait_for_way)
            self._wait_for_way(robot, now_s, pose_stamp)
            return
        if pose_stamp > self.last_answered:
            self._control(intention, robot, now_s, pose_stamp)
        if self._replan_due(intention, now_s):
            self._replan(intention, robot, now_s)

    def _replan_due(self, intention: IntentionView, now_s: float) -> bool:
        """Every REPLAN_PERIOD_S of sim time (which advances in float steps of control_dt: 2 x 0.1
        may sum to 0.19999...)."""
        return self.intention_id == intention.node_id and now_s - self.last_replan_s >= REPLAN_PERIOD_S - TIME_EPS_S

    def _start(self, intention: IntentionView, robot: Any, now_s: float) -> None:
        self.intention_id = intention.node_id
        self.goal = self.asked_goal = intention.goal
        self.route_rooms = intention.rooms
        self.started_s = now_s
        self.budget_m = 0.0
        self.following = False
        self.blocked_since = None
        if self.controller is None:
            self._refuse(self.controller_error)
            return
        pose = self.graph.world_pose(robot.id)
        self._plan(pose, now_s, reason=f"intention {intention.name}")
        if self.intention_id is not None:   # planned, or waiting for people to clear the way
            self.graph.update_node(robot.id, attrs={"nav_active": True})

    def _plan(self, pose: tuple[float, float, float], now_s: float, reason: str) -> bool:
        """Plan the intention's path; when there is none, wait up to BLOCKED_WAIT_S of sim time (people
        standing in a doorway or walking through it close it for a moment), then fail."""
        assert self.goal is not None
        try:
            self.map = self._build_map(now_s)
            try:
                path = self._plan_from(self.map, pose)
            except PlanningError:
                if self.blocked_since is None or now_s - self.blocked_since < STAND_IN_AFTER_S \
                        or not self._take_stand_in(self.map, now_s):
                    raise
                path = self._plan_from(self.map, pose)
        except PlannerFailed as exc:
            self._refuse(str(exc))
            return False
        except PlanningError as exc:
            if self.blocked_since is None:
                self.blocked_since = now_s
                self.rec.event(f"{format_clock(now_s)} no way to ({self.goal[0]:.2f}, {self.goal[1]:.2f}) now "
                               f"({exc}): waiting for it to clear", level="WARN")
            if now_s - self.blocked_since >= BLOCKED_WAIT_S:
                self._fail(f"no path to ({self.goal[0]:.2f}, {self.goal[1]:.2f}) for {BLOCKED_WAIT_S:.0f} s: {exc}")
            self.last_replan_s = now_s
            return False
        self.blocked_since = None
        points = self._route(pose, path)
        self._adopt(points, now_s, reason, path.cost, replan=False)
        return True

    def _take_stand_in(self, smap: SocialMap, now_s: float) -> bool:
        """The goal itself is occupied by people (its cell and everything within
        GOAL_TOLERANCE_M is not traversable): aim for the nearest free cell of the goal's room
        within STAND_IN_MAX_M of the intention's goal instead, keeping its heading.  False if the
        current goal is free (the way is what is blocked) or there is no such cell."""
        assert self.goal is not None
        cell = smap.spec.clipped_cells(np.array([[self.goal[0], self.goal[1]]]))
        if np.isfinite(smap.cost[cell][0]):
            return False
        goal = self.asked_goal or self.goal   # a stand-in taken in turn: still next to the goal asked
        room = self.scene.room_at(goal[0], goal[1])
        spot = stand_in_goal(smap.cost, smap.spec, (goal[0], goal[1]),
                             lambda x, y: self.scene.room_at(x, y) == room)
        if spot is None:
            return False
        self.rec.event(f"{format_clock(now_s)} goal ({goal[0]:.2f}, {goal[1]:.2f}) occupied by people: "
                       f"stopping next to it at ({spot[0]:.2f}, {spot[1]:.2f}), "
                       f"{math.hypot(spot[0] - goal[0], spot[1] - goal[1]):.1f} m away", level="WARN")
        self.log.info("goal (%.2f, %.2f) occupied by people: stand-in (%.2f, %.2f)", goal[0], goal[1], *spot)
        self.goal = (spot[0], spot[1], goal[2])
        return True

    def _wait_for_way(self, robot: Any, now_s: float, pose_stamp: float) -> None:
        """No path yet: answer each pose with a stop (the clock keeps its lockstep pace, so people
        move on) and plan again every replan period."""
        if pose_stamp > self.last_answered:
            self.last_answered = pose_stamp
            self.graph.update_node(robot.id, attrs={"cmd_vx": 0.0, "cmd_vy": 0.0, "cmd_omega": 0.0,
                                                    "cmd_stamp": pose_stamp})
        if now_s - self.last_replan_s >= REPLAN_PERIOD_S - TIME_EPS_S:
            self._plan(self.graph.world_pose(robot.id), now_s, reason="the way cleared")

    def _route(self, pose: tuple[float, float, float], path: Any) -> np.ndarray:
        """The path's cell centres with its ends replaced by the exact robot position and goal."""
        assert self.goal is not None
        return np.vstack([[pose[0], pose[1]], path.points_m[1:-1], [self.goal[0], self.goal[1]]])

    def _adopt(self, points: np.ndarray, now_s: float, reason: str, cost: float, replan: bool = True) -> None:
        self.global_points = points
        self._best_distance, self._progress_s = math.inf, now_s  # a new path: measure progress afresh
        self.following = True
        if self.controller is not None:
            self.controller.reset()   # a new path: the controller starts from it
        self.budget_m = max(self.budget_m, float(np.hypot(*np.diff(points, axis=0).T).sum()))
        self.last_replan_s = now_s
        self._publish_path(points, now_s, reason, cost, replan)

    def _remaining_global(self, pose: tuple[float, float, float]) -> np.ndarray:
        """The global path from the point nearest the robot on (the band may cut inflated corners,
        the global path is what the map judged free)."""
        points = self.global_points
        distance = np.hypot(points[:, 0] - pose[0], points[:, 1] - pose[1])
        nearest = int(np.argmin(distance))
        # Skip the stretch right at the robot: it may stand in an inflated cell (that is why it is
        # escaping); what matters is whether the way ahead is still free.
        ahead = nearest + int(np.argmax(distance[nearest:] > ESCAPE_SKIP_M)) if np.any(distance[nearest:] > ESCAPE_SKIP_M) \
            else len(points) - 1
        return points[ahead:]

    def _plan_from(self, smap: SocialMap, pose: tuple[float, float, float]) -> Any:
        """Plan from the robot to the goal; a start or goal in a non-traversable cell (someone
        stepped close, a goal on an inflated edge) moves to the nearest free cell (Nav2's tolerance)."""
        assert self.goal is not None
        start, goal = (pose[0], pose[1]), (self.goal[0], self.goal[1])
        for _ in range(3):
            try:
                return plan(smap, start, goal, planner=self.maps.planner, params=self.maps.planner_params,
                            replanner=self.replanner)
            except StartOccupied:
                start = nearest_free(smap.cost, smap.spec, start)
            except GoalOccupied:
                goal = nearest_free(smap.cost, smap.spec, goal, max_m=GOAL_TOLERANCE_M)
        return plan(smap, start, goal, planner=self.maps.planner, params=self.maps.planner_params,
                    replanner=self.replanner)

    def _replan(self, intention: IntentionView, robot: Any, now_s: float) -> None:
        del intention
        if not self.following or self.goal is None:
            return
        self.last_replan_s = now_s
        pose = self.graph.world_pose(robot.id)
        try:
            new_map = self._build_map(now_s)
            new_path = self._plan_from(new_map, pose)
        except PlannerFailed as exc:
            self._refuse(str(exc))
            return
        except PlanningError:
            return  # keep the current band; the goal may be momentarily blocked by a passer-by
        self.map = new_map
        grid = self.planner.grid(new_map)
        old_cost = path_cost(grid, new_map.spec, self._remaining_global(pose))
        new_cost = path_cost(grid, new_map.spec, new_path.points_m)
        if math.isinf(old_cost) or (old_cost > REPLAN_GAIN * new_cost and old_cost - new_cost > REPLAN_MIN_GAIN):
            why = "current path blocked" if math.isinf(old_cost) else f"cost {old_cost:.1f} -> {new_cost:.1f}"
            points = self._route(pose, new_path)
            self._adopt(points, now_s, f"replanned ({why})", new_path.cost)

    def _control(self, intention: IntentionView, robot: Any, now_s: float, pose_stamp: float) -> None:
        assert self.following and self.goal is not None
        pose = self.graph.world_pose(robot.id)
        control_input = ControlInput(pose=pose, velocity=self.last_cmd, path=self._ahead(pose),
                                     goal_theta=self.goal[2], limits=self.limits, dt_s=self.control_dt, now_s=now_s,
                                     people=self._people(),
                                     obstacles=self._obstacles(), scan=self._laser_points(robot, pose))
        assert self.controller is not None   # _start refuses an intention without one
        try:
            out = controllers.command(self.controller, self.controller_name, control_input)
        except controllers.ControllerFailed as exc:
            self.last_answered = pose_stamp
            self.last_cmd = (0.0, 0.0, 0.0)
            self._refuse(str(exc))   # _stop answers this pose with a zero command
            return
        vx, vy, omega = out.vx, out.vy, out.omega
        scale, contact = self._clearance_scale(robot, vx, vy)
        vx, vy = vx * scale, vy * scale
        if contact:  # pressed against something ahead: back off slowly while turning to the path
            vx, vy = -BACK_OFF_MPS * math.cos(math.atan2(vy, vx)), -BACK_OFF_MPS * math.sin(math.atan2(vy, vx))
        self.last_answered = pose_stamp
        passed = intention.pass_through and out.distance_to_goal_m < PASS_THROUGH_TOLERANCE_M
        if out.reached or passed:
            self._stop(robot, intention.node_id, IntentionState.DONE)
            self.rec.event(f"{format_clock(now_s)} reached goal of {intention.name} "
                           f"({now_s - self.started_s:.0f} s)")
            return
        if now_s - self.started_s > STALL_TIMEOUT_S + 4 * self.budget_m / max(self.cruise, 0.05):
            self._fail("timed out before reaching the goal")
            return
        remaining = out.distance_to_goal_m
        if remaining < self._best_distance - PROGRESS_M:
            self._best_distance, self._progress_s = remaining, now_s
        elif now_s - self._progress_s > STALL_S:
            # Recovery (as Nav2's): no progress for a while, so plan afresh from where the robot is.
            # The pose is answered with a stop: unanswered, the lockstep simulator would wait for
            # its wall-clock watchdog (a second) before it brakes and lets time flow again.
            self._progress_s = now_s
            self._recover(robot, now_s)
            vx = vy = omega = 0.0
        self.last_cmd = (vx, vy, omega)
        self.graph.update_node(robot.id, attrs={"cmd_vx": vx, "cmd_vy": vy, "cmd_omega": omega,
                                                "cmd_stamp": pose_stamp})
        if self.rec.enabled and int(pose_stamp * 10) % 5 == 0:
            band = getattr(self.controller, "band_points", None)   # what the controller follows, if it says
            self.decision.log_band((band if band is not None else control_input.path).tolist())

    def _people(self) -> np.ndarray:
        """The tracked people (K, 5), unless the controller says it does not read them
        (``reads_people = False``: the elastic band sees people through the laser only)."""
        if not getattr(self.controller, "reads_people", True):
            return np.zeros((0, 5))
        return tracked_people(self.graph, self.maps.params.grid.person_radius_m)

    def _ahead(self, pose: tuple[float, float, float]) -> np.ndarray:
        """The adopted global path from the point nearest the robot to the goal."""
        points = self.global_points
        nearest = int(np.argmin(np.hypot(points[:, 0] - pose[0], points[:, 1] - pose[1])))
        return points[nearest:] if len(points) - nearest >= 2 else points[-2:]

    def _obstacles(self) -> np.ndarray:
        """Walls, closed doors' leaves and object footprints as segments (rebuilt when a door's
        state changes)."""
        closed = tuple(closed_doors(self.graph))
        if self._segments is None or self._segments[0] != closed:
            self._segments = (closed, obstacle_segments(self.scene, self.maps.walls(self.graph)))
        return self._segments[1]

    def _recover(self, robot: Any, now_s: float) -> None:
        assert self.goal is not None
        pose = self.graph.world_pose(robot.id)
        self.last_cmd = (0.0, 0.0, 0.0)   # the robot is stopped this cycle: the controller restarts from rest
        try:
            smap = self._build_map(now_s)
            try:
                path = self._plan_from(smap, pose)
            except PlanningError:
                if not self._take_stand_in(smap, now_s):   # stalled: people stand on the goal?
                    raise
                path = self._plan_from(smap, pose)
        except PlannerFailed as exc:
            self._refuse(str(exc))
            return
        except PlanningError as exc:
            self.rec.event(f"{format_clock(now_s)} stalled and cannot replan: {exc}", level="WARN")
            return
        points = self._route(pose, path)
        self._adopt(points, now_s, "replanned (no progress: recovery)", path.cost)

    def _cuts_walls(self, points: np.ndarray, pose: tuple[float, float, float]) -> bool:
        """Does the band pass through a wall (deeper than half the inflation margin)?

        The band sees walls only through the laser, and its contraction outweighs the repulsion
        of a wall seen edge-on: on a door jamb it can slide across the wall (a robot once drove
        into the jamb of center_a's door_pt and stayed stuck there).  The map knows the walls,
        so a band that cuts them is dropped for the global path (which the map judged free)."""
        smap = self.map
        if smap is None or len(points) < 2:
            return False
        if self._wall_core is None or self._wall_core[0] is not smap.static:
            depth = smap.params.grid.robot_radius_m * 0.5
            self._wall_core = (smap.static, blocked_core(smap.static, smap.spec, depth))
        core = self._wall_core[1]
        spec = smap.spec
        dense = densify(points, spec.resolution / 2)
        far = np.hypot(dense[:, 0] - pose[0], dense[:, 1] - pose[1]) > ESCAPE_SKIP_M
        return bool(np.any(core[spec.clipped_cells(dense[far])]))

    def _clearance_scale(self, robot: Any, vx: float, vy: float) -> tuple[float, bool]:
        """Speed factor from the free space ahead in the direction of motion (laser), and whether
        the robot is in contact with something ahead."""
        view = RobotView.from_node(robot)
        ranges, angles = np.asarray(view.laser_ranges, dtype=float), np.asarray(view.laser_angles, dtype=float)
        if len(ranges) == 0 or len(ranges) != len(angles) or math.hypot(vx, vy) < 1e-6:
            return 1.0, False
        heading = math.atan2(vy, vx)
        ahead = np.abs(wrap_angle(angles - heading)) < math.radians(60)
        if not np.any(ahead):
            return 1.0, False
        free = float(np.min(ranges[ahead])) - self.scene.robot.radius
        return float(np.clip(free / SLOW_ZONE_M, 0.15, 1.0)), free < CONTACT_M

    def _stop(self, robot: Any, intention_id: int | None, state: str | None, reason: str = "") -> None:
        g = self.graph
        with g.transaction():
            g.update_node(robot.id, attrs={"nav_active": False, "cmd_vx": 0.0, "cmd_vy": 0.0, "cmd_omega": 0.0,
                                           "cmd_stamp": max(0.0, RobotView.from_node(robot).pose_stamp)})
            if intention_id is not None and state is not None and g.get_node(intention_id) is not None:
                g.update_node(intention_id, attrs={"state": state, "reason": reason})
        self.intention_id = None
        self.following = False
        self.last_cmd = (0.0, 0.0, 0.0)
        self.goal = self.asked_goal = None
        self.route_rooms = ()
        self._planned_s = None
        self.decision.clear()

    def _refuse(self, reason: str) -> None:
        """A plug-in (planner or controller) raised or answered something unusable: the robot gets
        a zero command, the mission fails naming the plug-in (its reason starts "plug-in refused",
        what ``chronav evaluate`` counts), and the agent counts it.  Nothing else stops: the next
        mission runs."""
        self.refusals += 1
        self.log.error("plug-in refused (%d so far): %s", self.refusals, reason)
        self._fail(f"plug-in refused: {reason}")

    def _fail(self, reason: str) -> None:
        robot = self._robot()
        self.log.warning("navigation failed: %s", reason)
        now_s = now_of(self.graph)
        self.rec.event(f"{format_clock(now_s or 0.0)} navigation failed: {reason}", level="ERROR")
        self._stop(robot, self.intention_id, IntentionState.FAILED, reason)

    def teardown(self) -> None:
        self.plans.close()

    # ----------------------------------------------------------------- outputs
    def _publish_path(self, points: np.ndarray, now_s: float, reason: str, cost: float, replan: bool) -> None:
        robot = self._robot()
        node = self.graph.get_node(self.intention_id) if self.intention_id is not None else None
        with self.graph.transaction():
            attrs = {"path_x": points[:, 0].tolist(), "path_y": points[:, 1].tolist(), "path_cost": float(cost),
                     "planned_s": now_s}
            self.graph.update_node(robot.id, attrs=attrs)
            if node is not None:
                intention = IntentionView.from_node(node)
                self.graph.update_node(intention.node_id, attrs={**attrs, "replans": intention.replans + int(replan)})
        self.rec.event(f"{format_clock(now_s)} path {reason}: {len(points)} points, cost {cost:.1f}")
        self._planned_s = now_s
        self.plans.adopted(now_s, points[:, 0], points[:, 1], cost, reason)
        self.decision.log_path(points.tolist())
        self.decision.log_stamp(self._stamp(now_s), self._stamp_anchor)   # every path is planned on a map of now_s
