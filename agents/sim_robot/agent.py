"""The simulated robot agent: owns the simulated world, the robot's body and the sim clock.

Clock policy (why): a 09:00-14:00 day must finish in minutes, yet control must see small, even
time steps. So the clock runs in four modes, decided every loop from the DSR:
- **driving**: a navigation is active (robot attr ``nav_active``): lockstep. The robot publishes
  its pose stamped ``pose_stamp``; it integrates the next ``control_dt`` only once the controller
  answered with ``cmd_stamp >= pose_stamp`` (or a wall-clock watchdog expires: the base then
  brakes, like a real motor driver with stale commands). Never faster than ``clock.rate``.
- **busy**: a mission is active but nothing drives (the executive is planning): real time.
- **busy** too when a mission is due and none is active (the executive is about to start it).
- **idle**: nothing to do: jump to the next mission / wait deadline when ``skip_idle``,
  otherwise run at ``clock.rate``.
- **starting**: the scene has missions the executive has not written yet: the clock stands still,
  so a mission due at the start of the day starts then, however long the agents take to start.

With ``-o robot=ros`` (``chronav launch --robot ros``) the robot is a ROS 2 robot: its pose,
velocity and laser come through the ROS bridge (agents/ros_bridge), which also sends it the
navigation's commands; this agent then only runs the clock at real time and the simulated world
(people, doors), with the robot's reported pose as their robot.

This agent decides the mode from the DSR; how fast each mode runs is ``ClockPace``
(agents/sim_robot/clock.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from agents.runtime.base import Agent
from agents.runtime.checked_graph import CheckedGraph
from agents.runtime.drawing.bodies import log_robot, log_true_people
from agents.runtime.recording import FramePacer, Recorder
from agents.sim_robot.clock import ClockPace
from agents.sim_robot.kinematics import Limits, Velocity, integrate, limit_command
from agents.sim_robot.laser import PERSON_RADIUS_M, Laser, polygon_segments, polyline_segments
from agents.lib.crowd.model import PersonTruth, RobotBody
from agents.world.building import closed_door_walls, footprint_polygons, scene_occupancy
from agents.world.dsr_readers import closed_doors
from agents.world.freshness import LOCKSTEP, observed_up_to
from agents.world.dsr_writers import set_doors, write_building, write_clock, write_ground_truth, write_robot
from agents.world.people import WorldFeed, manual_changes, new_crowd
from agents.world.timeline import doors_at, next_scheduled_event, unapplied_changes
from agents.world.vocabulary import (AGENDA, CLOCK, WORLD, ClockMode, EdgeType, IntentionKind, IntentionState,
                                     MissionState, MissionView, NodeType, intentions, missions)
from scenes.geometry import project_on_segments
from scenes.clock import format_clock

CONTROL_DT_S = 0.1
PEOPLE_HEADER = ("t", "name", "role", "x", "y", "theta", "vx", "vy", "group")
WATCHDOG_WALL_S = 1.0
BUSY_RATE = 1.0
#: the true world is drawn at most this often (sim s): every in-process tick, 10 Hz in real time
DRAW_EVERY_S = 0.1
AGENDA_HOLD_WALL_S = 2.0  # the idle clock waits this long (wall) for the agenda agent to apply a due change


@dataclass
class RobotState:
    x: float
    y: float
    theta: float
    velocity: Velocity


def mission_due(day: list[MissionView], now_s: float) -> bool:
    """A pending mission's time has come and none runs: the executive is about to start one.

    The one definition the clock's mode and its idle step share.  Not while another mission
    runs: the executive runs them one at a time, so the due one waits for it, and holding the
    clock for it (``busy_rate=0``) would hold a mission that waits for an activity to start
    forever (an in-process day without idle skips stalled: tests/unit/test_sim_clock_hold.py)."""
    if any(m.state == MissionState.ACTIVE for m in day):
        return False
    return any(m.state == MissionState.PENDING and m.time_s <= now_s for m in day)


class SimRobotAgent(Agent):
    kind = "sim_robot"

    def setup(self, graph: CheckedGraph, recorder: Recorder) -> None:
        self.graph = graph
        self.rec = recorder
        scene = self.scene
        robot = scene.robot
        self.omni = robot.kinematics == "omnidirectional"
        self.limits = Limits(robot.max_speed, robot.max_angular_speed, robot.max_acceleration)
        self._fixed_segments = np.vstack([polyline_segments(scene.walls), polygon_segments(footprint_polygons(scene))])
        self._occupancy = scene_occupancy(scene)   # a building map's wall cells, if the scene has a map
        self.laser = Laser(self._fixed_segments, robot.laser_rays, robot.laser_range, occupancy=self._occupancy)
        self._closed_doors: frozenset[str] = frozenset()
        self.watchdog_s = float(self.config.option("watchdog_s", str(WATCHDOG_WALL_S)))
        self.control_dt = float(self.config.option("control_dt", str(CONTROL_DT_S)))
        # busy_rate: sim seconds per wall second while agents plan; 0 holds the clock until they are
        # done, so a run's sim times do not depend on how fast this machine plans (chronav evaluate).
        self.clock = ClockPace(rate=float(self.config.option("rate", str(scene.clock.rate))),
                               busy_rate=float(self.config.option("busy_rate", str(BUSY_RATE))),
                               control_dt=self.control_dt, skip_idle=scene.clock.skip_idle)
        self.external = self.config.option("robot", "sim") == "ros"   # a ROS 2 robot reports its own pose
        # Perception in lockstep (-o perception_lockstep=1, chronav evaluate and in-process runs): the
        # clock moves on only once every perceiver (and the executive after them) has processed the
        # current time, so the observer detects people at every clock tick, not at whatever ticks its
        # loop happens to see (agents/world/freshness.LOCKSTEP).
        self.perception_lockstep = self.config.option("perception_lockstep", "0") == "1"
        self._perception_since: float | None = None
        # The bumper: a move that brings the body into contact is refused; moving away always works.
        self._contact_m = robot.radius * 0.9
        self._bumped = False
        self._write_static_world()
        self.state, self.now_s = self._resume_or_start()
        # The simulated people: one crowd, fed the scene's script and the agenda changes staff make
        # (agents/world/people.py); a restarted simulator replays the day up to now.
        self.crowd = new_crowd(self.world)
        self.feed = WorldFeed(self.world)
        self._people: tuple[PersonTruth, ...] = ()
        self._people_file = self._open_people()
        self._reanchor()
        self._waiting_since: float | None = None
        self._agenda_hold: tuple[tuple[str, ...], float] | None = None
        self._trajectory_file = self._open_trajectory()
        self._last_mode: ClockMode | None = None
        self._room_name: str | None = None
        self._trail: list[list[float]] = []
        self._trail_times: list[float] = []   # sim s of each trail point (the recording shows the last minutes)
        self._frames = FramePacer(DRAW_EVERY_S)
        self._publish()

    # ----------------------------------------------------------------- world setup
    def _write_static_world(self) -> None:
        """World root, rooms, doors and the clock: what the simulated building is."""
        g, scene = self.graph, self.scene
        with g.transaction():
            write_building(g, scene, doors_at(scene, scene.clock.start_s))
            if g.get_node_by_name(CLOCK) is None:
                write_clock(g, scene, scene.clock.start_s, self.clock.rate)

    def _resume_or_start(self) -> tuple[RobotState, float]:
        """A restarted simulator continues from the replicated pose and clock, not from the scene."""
        g, spec = self.graph, self.scene.robot
        now_s = float(g.get_node_by_name(CLOCK).attrs.get("now_s", self.scene.clock.start_s))
        node = g.get_node_by_name(spec.name)
        world = g.get_node_by_name(WORLD)
        edge = g.get_edge(world.id, node.id, EdgeType.RT) if node is not None else None
        if edge is not None:
            self.log.info("resuming robot at (%.2f, %.2f) t=%.1f", edge.attrs["x"], edge.attrs["y"], now_s)
            return RobotState(edge.attrs["x"], edge.attrs["y"], edge.attrs["theta"], Velocity()), now_s
        pose = (spec.pose.x, spec.pose.y, spec.pose.theta)
        write_robot(g, spec, pose, self.scene.room_at(spec.pose.x, spec.pose.y), self.laser.angles.tolist())
        return RobotState(*pose, Velocity()), now_s

    # ----------------------------------------------------------------- loop
    def _doors(self) -> None:
        """Scripted door events: each door takes the state of its latest due change (restart-safe),
        and a closed door blocks the laser and the base like a wall."""
        g = self.graph
        for name, is_open in set_doors(g, doors_at(self.scene, self.now_s)):
            self.rec.event(f"{format_clock(self.now_s)} door {name} {'opened' if is_open else 'closed'}")
        closed = frozenset(closed_doors(g))
        if closed != self._closed_doors:
            self._closed_doors = closed
            leaves = [wall.points for wall in closed_door_walls(self.scene, closed)]
            self.laser.segments = np.vstack([self._fixed_segments, polyline_segments(leaves)])

    def step(self) -> None:
        self._doors()
        mode = self._mode()
        if mode != self._last_mode:
            self._last_mode = mode
            self._reanchor()
            self._set_clock(mode=mode)
        wall_now = self.wall_clock()
        end_s = self.scene.clock.end_s
        if self.now_s >= end_s:
            self._set_clock(mode=ClockMode.FINISHED, finished=True)
            return
        if not self._perceived(wall_now):
            return
        if self.external:
            self._follow_external(wall_now, mode)
        elif mode == ClockMode.DRIVING:
            robot = self.graph.get_node_by_name(self.scene.robot.name)
            fresh = float(robot.attrs.get("cmd_stamp", -1.0)) >= float(robot.attrs.get("pose_stamp", 0.0))
            if not self.clock.driving_allows(wall_now, self.now_s):
                return
            if fresh:
                self._waiting_since = None
                cmd = Velocity(float(robot.attrs.get("cmd_vx", 0.0)), float(robot.attrs.get("cmd_vy", 0.0)),
                               float(robot.attrs.get("cmd_omega", 0.0)))
            else:
                self._waiting_since = self._waiting_since or wall_now
                if wall_now - self._waiting_since < self.watchdog_s:
                    return
                cmd = Velocity()  # stale command: brake, keep time flowing
            self._advance(self.control_dt, cmd)
        elif mode == ClockMode.STARTING:
            return
        elif mode == ClockMode.BUSY:
            dt = min(self.clock.busy_step(wall_now, self.now_s), end_s - self.now_s)
            if dt > 0:
                self._advance(dt, Velocity())
        else:
            if self._holding_for_agenda(wall_now):
                return
            event = min(self._next_event(), end_s)     # the day's end is the last event: no step runs past it
            target = self.clock.idle_skip(self.now_s, self._next_deadline(), end_s, event)
            if target is not None:
                # In pieces (ClockPace.idle_skip): the people walk through every skipped second
                # (agents/world/people.py); a scheduled event (agenda change, door, crowd routine) ends a piece.
                skipped_from = self.now_s
                self.skip_to(target)
                self.rec.event(f"{format_clock(self.now_s)} idle: clock skipped from {format_clock(skipped_from)} "
                               f"to {format_clock(self.now_s)}")
            else:
                # A mission is due and the executive is starting it: time runs as while agents plan.
                dt = self.clock.idle_step(wall_now, self.now_s, self._due_now(), event)
                if dt > 0:
                    self._advance(dt, Velocity())

    def _next_event(self) -> float:
        """The next scheduled event after now: a scripted agenda change or door event, or a crowd
        routine event (inf: none)."""
        scripted = next_scheduled_event(self.world, self.now_s)
        return min(math.inf if scripted is None else scripted, self.crowd.next_event_s(self.now_s))

    def _holding_for_agenda(self, wall_now: float) -> bool:
        """A scripted agenda change is due and the agenda agent has not applied it yet: the idle clock
        stands still (at most ``AGENDA_HOLD_WALL_S`` wall seconds, so a dead agenda agent cannot stop
        the day), so the change is stamped with its own time, not the end of the next skip."""
        log = self.graph.get_node_by_name(AGENDA)
        pending = unapplied_changes(self.world, self.now_s, log.attrs.get("applied", []) if log is not None else [])
        if not pending:
            self._agenda_hold = None
            return False
        if self._agenda_hold is None or self._agenda_hold[0] != pending:
            self._agenda_hold = (pending, wall_now)
        return wall_now - self._agenda_hold[1] < AGENDA_HOLD_WALL_S

    def _follow_external(self, wall_now: float, mode: ClockMode) -> None:
        """--robot ros: real time, the robot where the bridge last put it (no lockstep, no skips)."""
        if mode == ClockMode.STARTING:
            return
        dt = self.clock.external_step(wall_now, self.now_s)
        if dt <= 0:
            return
        g = self.graph
        robot, world = g.get_node_by_name(self.scene.robot.name), g.get_node_by_name(WORLD)
        edge = g.get_edge(world.id, robot.id, EdgeType.RT) if robot is not None and world is not None else None
        if edge is not None:
            a = robot.attrs
            self.state = RobotState(float(edge.attrs["x"]), float(edge.attrs["y"]), float(edge.attrs["theta"]),
                                    Velocity(float(a.get("v", 0.0)), float(a.get("vy", 0.0)), float(a.get("omega", 0.0))))
        self.now_s += dt
        self._publish()
        if self._trajectory_file is not None and mode == ClockMode.DRIVING:
            s = self.state
            self._trajectory_file.write(f"{self.now_s:.3f},{s.x:.4f},{s.y:.4f},{s.theta:.5f}\n")

    def _perceived(self, wall_now: float) -> bool:
        """With perception in lockstep: have the perceivers processed the current clock value?  A
        perceiver that does not answer within the watchdog (it died) no longer holds the clock."""
        if not self.perception_lockstep or observed_up_to(self.graph, self.now_s, LOCKSTEP, slack_s=0.0):
            self._perception_since = None
            return True
        self._perception_since = self._perception_since or wall_now
        if wall_now - self._perception_since < self.watchdog_s:
            return False
        self.rec.event(f"perception did not answer t={self.now_s:.1f} s within {self.watchdog_s:g} s: "
                       "the clock runs on", level="WARN")
        self._perception_since = None
        return True

    def _due_now(self) -> bool:
        """A pending mission's time has come and none runs (the executive is about to start it)."""
        return mission_due(missions(self.graph), self.now_s)

    def skip_to(self, t_s: float) -> None:
        """Jump the sim clock to ``t_s`` with the robot at rest, and carry out what is due by then
        (scripted doors), as the idle mode does when nothing is due before ``t_s``."""
        self.now_s = t_s
        self._doors()
        self._reanchor()
        self._publish()

    def _reanchor(self) -> None:
        self.clock.reanchor(self.wall_clock(), self.now_s)

    def _mode(self) -> ClockMode:
        g = self.graph
        robot = g.get_node_by_name(self.scene.robot.name)
        if robot is not None and robot.attrs.get("nav_active"):
            return ClockMode.DRIVING
        if any(n.attrs.get("state") == IntentionState.ACTIVE
               and n.attrs.get("kind", IntentionKind.NAVIGATE) != IntentionKind.WAIT
               for n in g.nodes_of_type(NodeType.INTENTION)):
            return ClockMode.BUSY
        day = missions(g)
        if self.scene.missions and not day:
            return ClockMode.STARTING  # the executive has not written the day's missions yet: time stands still
        if any(m.state == MissionState.ACTIVE for m in day) and not any(i.active for i in intentions(g)):
            return ClockMode.BUSY
        if mission_due(day, self.now_s):
            return ClockMode.BUSY  # a mission is due: let the executive start it now, not minutes of sim time later
        return ClockMode.IDLE

    def _next_deadline(self) -> float | None:
        """Earliest future time something is due: a pending mission, the end of a wait.

        While a mission is active (waiting for an activity), pending missions cannot start, so
        their times are not deadlines: the clock skips straight to the end of the wait."""
        day = missions(self.graph)
        busy = any(m.state == MissionState.ACTIVE for m in day)
        times = [] if busy else [m.time_s for m in day if m.state == MissionState.PENDING]
        times += [float(n.attrs["until_s"]) for n in self.graph.nodes_of_type(NodeType.INTENTION)
                  if n.attrs.get("state") == IntentionState.ACTIVE and n.attrs.get("kind") == IntentionKind.WAIT
                  and "until_s" in n.attrs]
        future = [t for t in times if t > self.now_s]
        due_now = [t for t in times if t <= self.now_s]
        if due_now:
            return None  # something is due already: let the executive act at this time
        return min(future) if future else None

    def _advance(self, dt: float, cmd: Velocity) -> None:
        state = self.state
        vel = limit_command(cmd, state.velocity, dt, self.limits, self.omni)
        x, y, theta = integrate(state.x, state.y, state.theta, vel, dt)
        if self._clearance(x, y) < self._contact_m and self._clearance(x, y) < self._clearance(state.x, state.y):
            # Bumper: the translation is refused; a round base may still turn in place.
            vel = Velocity(0.0, 0.0, vel.omega)
            x, y, theta = integrate(state.x, state.y, state.theta, vel, dt)
            if not self._bumped:
                self.rec.event(f"{format_clock(self.now_s)} bumper: motion blocked by an obstacle", level="WARN")
            self._bumped = True
        else:
            self._bumped = False
        self.state = RobotState(x, y, theta, vel)
        self.now_s += dt
        self._publish()
        if self._trajectory_file is not None and self._last_mode == ClockMode.DRIVING:
            self._trajectory_file.write(f"{self.now_s:.3f},{x:.4f},{y:.4f},{theta:.5f}\n")
            self._trail.append([x, y])
            self._trail_times.append(self.now_s)
            if len(self._trail) > 4000:   # the recording keeps minutes of trail, not the day's
                del self._trail[:2000], self._trail_times[:2000]
            if self._people_file is not None:
                self._people_file.writelines(
                    f"{self.now_s:.3f},{p.name},{p.role},{p.x:.4f},{p.y:.4f},{p.theta:.5f},{p.vx:.4f},{p.vy:.4f},{p.group}\n"
                    for p in self._people)

    def _clearance(self, x: float, y: float) -> float:
        """Distance from the robot's centre to the nearest wall, footprint or person body."""
        nearest = math.inf
        for p in self._people:
            nearest = min(nearest, math.hypot(p.x - x, p.y - y) - PERSON_RADIUS_M)
        segs = self.laser.segments
        if len(segs):
            nearest = min(nearest, float(np.min(project_on_segments((x, y), segs[:, :2], segs[:, 2:]).distance)))
        if self._occupancy is not None:
            nearest = min(nearest, self._occupancy.clearance(x, y, reach_m=max(2 * self._contact_m, 0.5)))
        return nearest

    def _open_trajectory(self):
        """Ground-truth poses while driving, appended (a restarted simulator continues the file)."""
        if self.config.run_dir is None:
            return None
        path = self.config.run_dir / "trajectory.csv"
        new = not path.exists()
        handle = path.open("a", encoding="utf-8", buffering=1)
        if new:
            handle.write("t,x,y,theta\n")
        return handle

    def _open_people(self):
        """Every person's true pose and velocity at each trajectory sample (``people.csv`` beside
        ``trajectory.csv``: what `chronav metrics` measures the robot's manners against)."""
        if self.config.run_dir is None:
            return None
        path = self.config.run_dir / "people.csv"
        new = not path.exists()
        handle = path.open("a", encoding="utf-8", buffering=1 << 16)
        if new:
            handle.write(",".join(PEOPLE_HEADER) + "\n")
        return handle

    def teardown(self) -> None:
        for handle in (self._trajectory_file, self._people_file):
            if handle is not None:
                handle.close()

    def _update_people(self) -> None:
        """Bring the crowd to the sim time: staff's agenda changes from the DSR's log, the robot
        (people avoid it while it drives, and walk round it and stand clear of it at rest)."""
        log = self.graph.get_node_by_name(AGENDA)
        if log is not None:
            manual = manual_changes(log.attrs.get("applied", []), log.attrs.get("changes", []), self.world)
            if manual != self.feed.manual:
                self.feed = WorldFeed(self.world, manual)
        s = self.state
        vx = vy = 0.0
        if self._last_mode == ClockMode.DRIVING:
            vx = s.velocity.vx * math.cos(s.theta) - s.velocity.vy * math.sin(s.theta)
            vy = s.velocity.vx * math.sin(s.theta) + s.velocity.vy * math.cos(s.theta)
        self.crowd.advance(self.now_s, self.feed, RobotBody(s.x, s.y, vx, vy, self.scene.robot.radius))
        self._people = self.crowd.at(self.now_s)

    def _publish(self) -> None:
        """Pose, laser and clock in ONE delta, so readers never see a pose from another time."""
        g, s = self.graph, self.state
        self._update_people()
        people_xy = np.array([[p.x, p.y] for p in self._people]).reshape(-1, 2)
        robot = g.get_node_by_name(self.scene.robot.name)
        if self.external:   # the ROS robot's own laser, as the bridge wrote it
            ranges = np.asarray(robot.attrs.get("laser_ranges") or [self.laser.max_range] * len(self.laser.angles))
        else:
            ranges = self.laser.scan(s.x, s.y, s.theta, people_xy)
        world = g.get_node_by_name(WORLD)
        room = self._room_change(s.x, s.y)
        with g.transaction():
            if not self.external:
                g.insert_or_assign_edge(world.id, robot.id, EdgeType.RT, attrs={"x": s.x, "y": s.y, "theta": s.theta})
            if room is not None:
                for edge in g.edges_from(robot.id, EdgeType.IN):
                    g.delete_edge(robot.id, edge.dst, EdgeType.IN)
                g.insert_or_assign_edge(robot.id, room.id, EdgeType.IN, attrs={})
            if not self.external:
                g.update_node(robot.id, attrs={"pose_stamp": self.now_s, "v": s.velocity.vx, "vy": s.velocity.vy,
                                                "omega": s.velocity.omega, "laser_ranges": ranges.tolist()})
            g.update_node(g.get_node_by_name(CLOCK).id, attrs={"now_s": self.now_s})
            write_ground_truth(g, self._people, self.now_s)
        self.rec.set_time(self.now_s)
        if self.rec.enabled and self._frames.due(self.now_s):
            self._log_frame(ranges)

    def _room_change(self, x: float, y: float):
        """The room node to link with `in` when the robot crossed into another room, else None."""
        name = self.scene.room_at(x, y)
        if name is None or name == self._room_name:
            return None
        self._room_name = name
        return self.graph.get_node_by_name(name)

    def _set_clock(self, **attrs: object) -> None:
        clock = self.graph.get_node_by_name(CLOCK)
        if any(clock.attrs.get(k) != v for k, v in attrs.items()):
            self.graph.update_node(clock.id, attrs=dict(attrs))

    def _log_frame(self, ranges: np.ndarray) -> None:
        s = self.state
        log_robot(self.rec, self.scene.robot.name, self.scene.robot.radius, (s.x, s.y, s.theta),
                  math.hypot(s.velocity.vx, s.velocity.vy), self.laser.points(s.x, s.y, s.theta, ranges), self._trail,
                  self._trail_times, now_s=self.now_s)
        log_true_people(self.rec, [p.name for p in self._people], [(p.x, p.y) for p in self._people])
