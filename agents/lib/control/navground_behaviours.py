"""The field's established local navigation methods as chronav local controllers, through navground.

navground (IDSIA's navigation playground, PyPI ``navground``) implements ORCA, HRVO, the
human-like behaviour (HL) and the social force model behind one API: a `Behavior` is given the
robot's pose, twist, kinematics and radius, an environment state (neighbours as moving discs, walls
as line segments) and a target, and answers one velocity command.  `NavgroundController` wraps one
such behaviour in chronav's `LocalController` protocol so that a study can put the field's methods
beside chronav's elastic band with nothing else changed: same global path, same people, same walls,
same robot limits, same goal tolerance.

How the wrapper drives a behaviour, each cycle:

* **Path following.**  navground's behaviours steer towards a target; chronav's global path is
  followed by giving them a *carrot*: the point ``lookahead_m`` further along the path than the
  robot's projection on it (the goal when less path is left), as chronav's own control law does.
* **People** become navground neighbours (position, velocity, radius), **walls and object
  footprints' edges** obstacles in the form each behaviour handles (`NavgroundController._set_walls`);
  only those within the behaviour's ``horizon_m`` are passed (the behaviours ignore farther ones
  anyway, and it bounds the step's cost).
* **Limits.**  The robot's radius, maximum speed and angular speed and its drive (differential:
  navground's two-wheel differential kinematics, with the linear and angular limits independent as
  in chronav's law; omni: its omnidirectional kinematics).  Near the goal the behaviour's optimal
  speed is capped by ``sqrt(2 a_max d)`` so that the robot can stop on the goal, and the linear
  acceleration from the current command is limited to ``max_accel_mps2`` (the behaviours assume
  instant velocity changes; the robot does not have them).
* **Arrival** is chronav's, not navground's: inside ``goal_tolerance_m`` (0.1 m) the robot stops,
  then turns to ``goal_theta`` when given, until within ``goal_heading_tolerance_rad`` (0.1 rad);
  ``reached`` is True once both hold.
* **Guard.**  A behaviour handed a degenerate scene (a person on top of the robot) may answer NaN:
  any non-finite component is replaced by a stop, so the command is always finite.

Each behaviour's own parameters are a frozen pydantic model with the defaults of navground and the
original papers (see each field's description and docs/baselines.md).

Frames: ControlInput's world frame in, robot-frame (vx, vy, omega) out; navground is asked for its
command in the relative (robot) frame, so no rotation is done here.
"""

from __future__ import annotations

import math
from typing import Any

import navground.core as core
import numpy as np
from navground.core.behaviors.social_force import SocialForceBehavior
from pydantic import BaseModel, ConfigDict, Field

from agents.lib.control.control_law import carrot, clip, final_turn, stopping_speed
from agents.lib.control.protocol import ControlCommand, ControlInput, FloatArray, LocalController, RobotLimits
from scenes.geometry import project_on_segments


class NavgroundConfigError(ValueError):
    """A behaviour parameter navground does not accept; the message names behaviour and parameter."""


# ------------------------------------------------------------------------------------- parameters
class NavgroundParams(BaseModel):
    """What every navground behaviour is given: chronav's path following and arrival, and
    navground's common `Behavior` properties."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    safety_margin_m: float = Field(0.05, ge=0.0, description=(
        "navground Behavior.safety_margin: clearance kept from walls and people beyond the bodies' "
        "radii (navground's default is 0). Small because the scenes' doors are 1.2 m wide for a "
        "0.6 m robot: 0.3 m each side, and a larger wall margin closes them (chronav's choice)"))
    social_margin_m: float = Field(0.1, ge=0.0, description=(
        "navground Behavior.social_margin (constant): clearance kept from people only, on top of "
        "the safety margin (navground's default is 0; chronav's choice)"))
    horizon_m: float = Field(5.0, gt=0.0, description=(
        "navground Behavior.horizon: radius of the environment the behaviour considers "
        "(navground default); farther people and walls are not passed"))
    rotation_tau_s: float = Field(0.5, gt=0.0, description=(
        "navground Behavior.rotation_tau: relaxation time of the turn towards the velocity, "
        "omega = heading error / tau (navground default)"))
    lookahead_m: float = Field(1.0, gt=0.0, description=(
        "carrot distance along chronav's path (navground's Behavior.path_look_ahead default)"))
    goal_tolerance_m: float = Field(0.1, gt=0.0, description="stop within this of the goal (chronav's control law)")
    goal_heading_tolerance_rad: float = Field(0.1, gt=0.0, description=(
        "then turn to goal_theta within this (chronav's control law)"))
    heading_gain: float = Field(2.0, gt=0.0, description=(
        "rad/s per rad of the final turn to goal_theta (chronav's control law)"))

    def behaviour_properties(self) -> dict[str, float | int | bool]:
        """The behaviour's own navground properties, by navground name."""
        return {}


class OrcaParams(NavgroundParams):
    """Optimal Reciprocal Collision Avoidance: van den Berg, Guy, Lin and Manocha, "Reciprocal
    n-body collision avoidance", Robotics Research (ISRR 2009), Springer STAR 70, 2011; navground
    wraps the authors' RVO2 library."""

    social_margin_m: float = Field(0.25, ge=0.0, description=(
        "ORCA leaves half of each avoidance to the other agent (reciprocity), and a person does not "
        "run ORCA; 0.25 m keeps a differential robot clear of a person who walks at it without "
        "giving way (chronav's choice, tested; navground's default is 0)"))
    time_horizon_s: float = Field(10.0, gt=0.0, description=(
        "tau of the paper: the velocity obstacles of neighbours are truncated at this time "
        "(navground ORCA.time_horizon default)"))
    static_time_horizon_s: float = Field(2.0, gt=0.0, description=(
        "the same for walls (RVO2's timeHorizonObst). navground's default, 10 s, caps the speed "
        "towards a wall 3 m away at 0.3 m/s: the robot crawled a 13 m path of icra_usecase in "
        "136 s; 2 s: 35 s (chronav's choice, tested)"))
    treat_obstacles_as_agents: bool = Field(True, description=(
        "static discs as RVO agents with zero velocity (navground default; chronav passes walls "
        "as line segments, which RVO2 handles as obstacles either way)"))
    effective_center: bool = Field(False, description=(
        "plan for a point ahead of a differential robot's axle (navground default: off)"))

    def behaviour_properties(self) -> dict[str, float | int | bool]:
        return {"time_horizon": self.time_horizon_s, "static_time_horizon": self.static_time_horizon_s,
                "treat_obstacles_as_agents": self.treat_obstacles_as_agents,
                "effective_center": self.effective_center}


class HrvoParams(NavgroundParams):
    """Hybrid Reciprocal Velocity Obstacle: Snape, van den Berg, Guy and Manocha, "The Hybrid
    Reciprocal Velocity Obstacle", IEEE Transactions on Robotics 27(4), 2011; navground wraps the
    authors' HRVO library."""

    social_margin_m: float = Field(0.1, ge=0.0, description=(
        "HRVO shares each avoidance with the other agent too, but less than ORCA (the hybrid "
        "obstacle); 0.1 m keeps a differential robot clear of a person who walks at it without "
        "giving way (chronav's choice, tested; navground's default is 0)"))
    uncertainty_offset: float = Field(0.0, ge=0.0, description=(
        "widening of the velocity obstacles for sensing uncertainty (the HRVO library's "
        "uncertaintyOffset; navground HRVO.uncertainty_offset default: none)"))
    wall_range_m: float = Field(1.0, gt=0.0, description=(
        "walls reach HRVO as discs only this near. HRVO's velocity obstacles have no time horizon: "
        "in a closed room every direction meets a wall, and with the walls within 1.5 m the robot "
        "froze 0.7 m before a goal 1 m from a corner of icra_usecase; beyond that, its cost grows "
        "steeply with the number of discs (192 within 5 m: 6 ms a step). chronav's choice, tested"))
    wall_disc_radius_m: float = Field(0.1, gt=0.0, description=(
        "walls reach HRVO as rows of discs of this radius, one every two radii: walls 0.2 m thick "
        "that the robot cannot slip between, and a 1.2 m door stays open. Thicker discs do not keep "
        "HRVO farther from a wall's end (0.15 m: 0.02 m farther; 0.2 m: closed a door of "
        "icra_usecase). chronav's choice, tested"))

    def behaviour_properties(self) -> dict[str, float | int | bool]:
        return {"uncertainty_offset": self.uncertainty_offset}


class HlParams(NavgroundParams):
    """Human-like: Guzzi, Giusti, Gambardella, Theraulaz and Di Caro, "Human-friendly robot
    navigation in dynamic environments", ICRA 2013 (after Moussaïd, Helbing and Theraulaz, "How
    simple rules determine pedestrian behavior and crowd disasters", PNAS 108(17), 2011):
    the direction that minimises the distance to the target given the free distance to collision
    in each direction, at the speed that keeps ``eta`` from a collision."""

    tau_s: float = Field(0.125, ge=0.0, description=(
        "relaxation time of the velocity towards the desired one: higher, gentler accelerations "
        "(navground HL.tau default)"))
    eta_s: float = Field(0.5, gt=0.0, description=(
        "time kept away from a collision: speed = free distance / eta, as in Moussaïd et al. "
        "(navground HL.eta default)"))
    aperture_rad: float = Field(math.pi, gt=0.0, le=math.pi, description=(
        "half-angle of the sector of candidate directions (navground HL.aperture default: all "
        "around)"))
    resolution: int = Field(101, ge=1, le=361, description=(
        "number of candidate directions in the sector (navground HL.resolution default)"))
    epsilon_m: float = Field(0.0, ge=0.0, description=(
        "obstacles nearer than this push the robot away (navground HL.epsilon default: off)"))
    barrier_angle_rad: float = Field(math.pi / 2, ge=0.0, description=(
        "a virtually colliding obstacle is ignored beyond this angle from the direction "
        "(navground HL.barrier_angle default)"))

    def behaviour_properties(self) -> dict[str, float | int | bool]:
        return {"tau": self.tau_s, "eta": self.eta_s, "aperture": self.aperture_rad,
                "resolution": self.resolution, "epsilon": self.epsilon_m,
                "barrier_angle": self.barrier_angle_rad}


class SocialForceParams(NavgroundParams):
    """Social force: Helbing and Molnár, "Social force model for pedestrian dynamics", Physical
    Review E 51(5), 4282, 1995 (navground's implementation and defaults, which are the paper's),
    with the bodies' radii as in Helbing, Farkas and Vicsek, "Simulating dynamical features of
    escape panic", Nature 407, 2000: the people's potential falls with the distance between the
    bodies' edges (and the safety and social margins), not between their centres (see
    `BodySocialForce`)."""

    social_margin_m: float = Field(0.25, ge=0.0, description=(
        "added with the safety margin to the bodies' radii in the people's potential; 0.25 m keeps "
        "a differential robot, which cannot back away, clear of a person who walks at it without "
        "giving way (chronav's choice, tested)"))
    tau_s: float = Field(0.3, gt=0.0, description=(
        "relaxation time towards the desired velocity. The paper's 0.5 s is for a pedestrian "
        "wanting 1.34 m/s (a pull of 2.7 m/s^2 from rest); a robot wanting 0.6 m/s would pull "
        "with 1.2 m/s^2, and the paper's wall potential then holds it before a 1.2 m door of "
        "icra_usecase. 0.3 s pulls with 2 m/s^2 and passes (chronav's choice, tested)"))
    step_duration_s: float = Field(1.0, gt=0.0, description=(
        "step duration Delta t of the elliptical repulsion of a moving person (navground default)"))
    phi_rad: float = Field(1.75, gt=0.0, description=(
        "half-angle of the field of sight (paper: 2 phi = 200 deg, i.e. phi = 1.75 rad)"))
    c: float = Field(0.5, ge=0.0, description="weight of forces from outside the field of sight (paper: 0.5)")
    v_a: float = Field(2.1, ge=0.0, description="people's repulsive potential V0, m^2/s^2 (paper: 2.1)")
    v_r: float = Field(0.3, gt=0.0, description="its length scale sigma, m (paper: 0.3)")
    u_a: float = Field(10.0, ge=0.0, description="walls' repulsive potential U0, m^2/s^2 (paper: 10)")
    u_r: float = Field(0.2, gt=0.0, description="its length scale R, m (paper: 0.2)")

    def behaviour_properties(self) -> dict[str, float | int | bool]:
        return {"tau": self.tau_s, "step_duration": self.step_duration_s, "phi": self.phi_rad,
                "c": self.c, "v_a": self.v_a, "v_r": self.v_r, "u_a": self.u_a, "u_r": self.u_r}


# ---------------------------------------------------------------------------------- social force
class BodySocialForce(SocialForceBehavior):
    """navground's social force with the bodies' radii, vectorised over people and walls.

    Why: navground's implementation (as the 1995 paper) measures the repulsive potentials from the
    people's centres and ignores the robot's radius, so with the paper's constants
    (V0 = 2.1 m^2/s^2, sigma = 0.3 m) a 0.3 m robot walks into a 0.3 m person.  Here the distance
    ``b`` of the paper (the semi-minor axis of the ellipse with foci at the person and at the
    person one ``step_duration`` ahead) is reduced by both radii and the safety and social
    margins, as in Helbing, Farkas and Vicsek (2000).  Walls keep the paper's centre distance: U0 = 10 m^2/s^2 at
    R = 0.2 m already pushes at 11 m/s^2 when the robot's edge touches one, and measured from the
    edge it would hold the robot a metre off every wall.  Everything else is the paper's:
    relaxation towards the desired velocity in ``tau``, exponential potentials, forces from
    outside the field of sight ``phi`` weighted by ``c``.  numpy over all people and walls at once
    keeps a step with 30 people and 20 walls at 0.2 ms (navground's loops over Python objects:
    1.1 ms).
    """

    def __init__(self, kinematics: Any = None, radius: float = 0.0) -> None:
        super().__init__(kinematics, radius)
        self.people = np.zeros((0, 5))
        self.segments = np.zeros((0, 4))
        self.wall_clearance = 0.0   # the paper's centre distance, see the class docstring

    def desired_velocity_towards_velocity(self, target_velocity: Any, time_step: Any) -> Any:
        target = np.asarray(target_velocity, dtype=np.float64)
        speed = float(np.hypot(target[0], target[1]))
        if speed == 0.0:
            return np.zeros(2)
        e = target / speed
        position = np.asarray(self.position, dtype=np.float64)
        force = (target - np.asarray(self.velocity, dtype=np.float64)) / max(self.tau, 1e-3)
        clearance = self.radius + self.safety_margin + self.social_margin.get()
        if len(self.people):
            force += self._weighted(self._people_forces(position, clearance), e)
        if len(self.segments):
            force += self._weighted(self._wall_forces(position, self.wall_clearance), e)
        return np.asarray(self.actuated_twist.velocity, dtype=np.float64) + float(time_step) * force

    def _people_forces(self, position: FloatArray, clearance: float) -> FloatArray:
        p = self.people
        delta = position - p[:, :2]
        ahead = delta - p[:, 2:4] * self.step_duration
        n1 = np.maximum(np.hypot(delta[:, 0], delta[:, 1]), 1e-9)
        n2 = np.maximum(np.hypot(ahead[:, 0], ahead[:, 1]), 1e-9)
        n3 = np.hypot(p[:, 2], p[:, 3]) * self.step_duration
        b = 0.5 * np.sqrt(np.maximum((n1 + n2) ** 2 - n3 ** 2, 1e-18))
        # d b / d position = (n1 + n2) (delta / n1 + ahead / n2) / (4 b)
        grad = ((n1 + n2) / (4.0 * b))[:, None] * (delta / n1[:, None] + ahead / n2[:, None])
        gap = b - (clearance + p[:, 4])
        magnitude = self.v_a / self.v_r * np.exp(-np.clip(gap, -2.0, None) / self.v_r)
        return magnitude[:, None] * grad

    def _wall_forces(self, position: FloatArray, clearance: float) -> FloatArray:
        s = self.segments
        projection = project_on_segments(position, s[:, :2], s[:, 2:])
        distance = np.maximum(projection.distance, 1e-9)
        away = (position - projection.closest) / distance[:, None]
        gap = distance - clearance
        magnitude = self.u_a / self.u_r * np.exp(-np.clip(gap, -2.0, None) / self.u_r)
        return magnitude[:, None] * away

    def _weighted(self, forces: FloatArray, e: FloatArray) -> FloatArray:
        """Sum of the forces, those whose source is outside the field of sight weighted by c."""
        norm = np.hypot(forces[:, 0], forces[:, 1])
        in_sight = -(forces @ e) > self.cos_phi * norm   # the source is opposite the push
        weights = np.where(in_sight, 1.0, self.c)
        return np.asarray((weights[:, None] * forces).sum(axis=0), dtype=np.float64)


# ------------------------------------------------------------------------------------- controller
class NavgroundController:
    """One navground behaviour type as a chronav `LocalController` (see the module docstring)."""

    def __init__(self, behaviour_type: str, limits: RobotLimits, params: NavgroundParams | None = None) -> None:
        if behaviour_type not in core.Behavior.types:
            known = ", ".join(t for t in core.Behavior.types if t)
            raise NavgroundConfigError(f"navground behaviour {behaviour_type!r} is not installed; known: {known}")
        if limits.drive not in ("differential", "omni"):
            raise NavgroundConfigError(f"limits.drive: expected 'differential' or 'omni', got {limits.drive!r}")
        self.behaviour_type = behaviour_type
        self.limits = limits
        self.params = params if params is not None else PARAMS_BY_BEHAVIOUR.get(behaviour_type, NavgroundParams)()
        self._behaviour = self._make_behaviour()

    def reset(self) -> None:
        """A fresh behaviour: HL's relaxed velocity and social force's integrated one are forgotten."""
        self._behaviour = self._make_behaviour()

    def command(self, control_input: ControlInput) -> ControlCommand:
        p, limits = self.params, control_input.limits
        if limits != self.limits:   # the kinematics are the behaviour's: a new robot, a new behaviour
            self.limits = limits
            self._behaviour = self._make_behaviour()
        x, y, theta = (float(v) for v in control_input.pose)
        if not all(math.isfinite(v) for v in (x, y, theta)):
            raise ValueError(f"ControlInput.pose: expected finite (x, y, theta), got {control_input.pose}")
        if not (control_input.dt_s > 0.0 and math.isfinite(control_input.dt_s)):
            raise ValueError(f"ControlInput.dt_s: expected a positive finite period, got {control_input.dt_s}")
        path = _path(control_input.path, (x, y))
        goal = path[-1]
        distance = math.hypot(goal[0] - x, goal[1] - y)
        if distance <= p.goal_tolerance_m:
            omega, done = self._final_turn(theta, control_input.goal_theta, limits)
            return ControlCommand(0.0, 0.0, omega, done, distance)
        target, remaining = carrot((x, y, theta), path, p.lookahead_m)   # chronav's control law's carrot
        left = max(remaining, distance)
        behaviour = self._behaviour
        behaviour.optimal_speed = min(limits.max_speed_mps, stopping_speed(left, p.goal_tolerance_m,
                                                                            limits.max_accel_mps2))
        behaviour.pose = core.Pose2((x, y), theta)
        vx0, vy0, w0 = (float(v) if math.isfinite(v) else 0.0 for v in control_input.velocity)
        if limits.drive == "differential":
            vy0 = 0.0   # a differential robot has no sideways velocity, whatever it was told
        current = core.Twist2((vx0, vy0), w0, core.Frame.relative)
        behaviour.twist = current
        behaviour.actuated_twist = current
        people = _near_people(control_input.people, (x, y), p.horizon_m)
        segments = _near_segments(control_input.obstacles, (x, y), p.horizon_m)
        if isinstance(behaviour, BodySocialForce):
            behaviour.people, behaviour.segments = people, segments
        else:
            state = behaviour.environment_state
            state.neighbors = [core.Neighbor((r[0], r[1]), r[4], (r[2], r[3]), i) for i, r in enumerate(people)]
            self._set_walls(state, segments, (x, y))
        near_goal = left <= p.lookahead_m
        # Half chronav's tolerance: navground (in float32) must not stop just outside chronav's.
        behaviour.target = core.Target.Point(target, p.goal_tolerance_m / 2 if near_goal else 0.0)
        twist = behaviour.compute_cmd(control_input.dt_s, core.Frame.relative, True)
        vx, vy = (float(v) for v in twist.velocity)
        omega = float(twist.angular_speed)
        if not all(math.isfinite(v) for v in (vx, vy, omega)):
            vx, vy, omega = 0.0, 0.0, 0.0
        if limits.drive == "differential":
            vy = 0.0
        vx, vy = _limit_acceleration((vx0, vy0), (vx, vy), limits.max_accel_mps2 * control_input.dt_s)
        omega = clip(omega, limits.max_angular_speed_radps)
        return ControlCommand(vx, vy, omega, False, left)

    # -- internals
    def _make_behaviour(self) -> Any:
        limits = self.limits
        behaviour = (BodySocialForce() if self.behaviour_type == "SocialForce"
                     else core.Behavior.make_type(self.behaviour_type))
        if behaviour is None:
            raise NavgroundConfigError(f"navground could not make a {self.behaviour_type!r} behaviour")
        if limits.drive == "differential":
            # Wheel speed unbounded, linear and angular speeds bounded independently, no reversing:
            # the same box of commands as chronav's differential control law, except that navground
            # also caps the angular speed at 2 max_forward_speed / wheel_axis, i.e. at
            # max_speed / radius with the wheels a diameter apart (2 rad/s for the scenes' default robot,
            # above its 1.2 rad/s limit).
            behaviour.kinematics = core.kinematics.TwoWheelsDifferentialDriveKinematics(
                max_speed=math.inf, wheel_axis=2.0 * limits.radius_m,
                max_angular_speed=limits.max_angular_speed_radps,
                max_forward_speed=limits.max_speed_mps, max_backward_speed=0.0)
        else:
            behaviour.kinematics = core.kinematics.OmnidirectionalKinematics(
                max_speed=limits.max_speed_mps, max_angular_speed=limits.max_angular_speed_radps)
        behaviour.radius = limits.radius_m
        behaviour.safety_margin = self.params.safety_margin_m
        behaviour.social_margin.set(self.params.social_margin_m)
        behaviour.horizon = self.params.horizon_m
        behaviour.rotation_tau = self.params.rotation_tau_s
        behaviour.heading_behavior = core.Behavior.Heading.velocity
        known = behaviour.properties
        for name, value in self.params.behaviour_properties().items():
            if name not in known:
                raise NavgroundConfigError(f"navground {self.behaviour_type}: no property {name!r} "
                                           f"({type(self.params).__name__} is not its parameters; it has "
                                           f"{', '.join(sorted(known))})")
            behaviour.set(name, value)
            if not _same(behaviour.get(name), value):   # navground's set fails silently
                raise NavgroundConfigError(f"navground {self.behaviour_type}: property {name!r} = {value!r} "
                                           f"was not accepted (it reads {behaviour.get(name)!r})")
        return behaviour

    def _set_walls(self, state: Any, segments: FloatArray, xy: tuple[float, float]) -> None:
        """The walls as each behaviour can see them (measured with navground 0.7):

        * ORCA: line obstacles (RVO2's polygonal obstacles, vertices included);
        * HL: line obstacles plus each segment's two ends as point obstacles: HL's line obstacles
          have no end caps, and passing a wall's end without them the robot's body went 0.05 m
          (differential) and 0.13 m (omni) over it;
        * HRVO: navground's HRVO ignores line obstacles (only neighbours and discs reach the HRVO
          library), so each wall is a row of discs (`HrvoParams.wall_disc_radius_m`,
          `HrvoParams.wall_range_m`).
        """
        if isinstance(self.params, HrvoParams):
            radius = self.params.wall_disc_radius_m
            reach = min(self.params.horizon_m, self.params.wall_range_m)
            state.line_obstacles = []
            state.static_obstacles = [core.Disc((px, py), radius) for px, py in _wall_discs(segments, xy, reach, radius)]
            return
        state.line_obstacles = [core.LineSegment((r[0], r[1]), (r[2], r[3])) for r in segments]
        if self.behaviour_type == "HL":
            ends = np.unique(np.vstack([segments[:, :2], segments[:, 2:]]), axis=0) if len(segments) else segments
            state.static_obstacles = [core.Disc((e[0], e[1]), 0.0) for e in ends]

    def _final_turn(self, theta: float, goal_theta: float | None, limits: RobotLimits) -> tuple[float, bool]:
        if goal_theta is not None and not math.isfinite(goal_theta):
            goal_theta = None     # a goal heading that is not a number: arrive without turning
        return final_turn(theta, goal_theta, self.params.goal_heading_tolerance_rad, self.params.heading_gain,
                          limits.max_angular_speed_radps)


# -------------------------------------------------------------------------------------- factories
# The controller registry's entries: the robot's limits in, a controller with the documented
# defaults out.  Other parameters: NavgroundController(type, limits, OrcaParams(...)) and so on.
def orca(limits: RobotLimits) -> LocalController:
    """ORCA (van den Berg et al. 2011) through navground."""
    return NavgroundController("ORCA", limits, OrcaParams())


def hrvo(limits: RobotLimits) -> LocalController:
    """HRVO (Snape et al. 2011) through navground."""
    return NavgroundController("HRVO", limits, HrvoParams())


def human_like(limits: RobotLimits) -> LocalController:
    """navground's human-like behaviour HL (Guzzi et al. 2013)."""
    return NavgroundController("HL", limits, HlParams())


def social_force(limits: RobotLimits) -> LocalController:
    """The social force model (Helbing and Molnár 1995) through navground."""
    return NavgroundController("SocialForce", limits, SocialForceParams())




# ---------------------------------------------------------------------------------------- helpers
def _path(path: FloatArray, xy: tuple[float, float]) -> FloatArray:
    """The path as finite (N >= 2, 2) points; a one-point path is the segment robot -> goal."""
    pts = np.asarray(path, dtype=np.float64).reshape(-1, 2)
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    if len(pts) == 0:
        raise ValueError("ControlInput.path: no finite point; a controller needs at least the goal")
    if len(pts) == 1:
        pts = np.vstack([xy, pts])
    return pts


def _near_people(people: FloatArray, xy: tuple[float, float], horizon_m: float) -> FloatArray:
    """The finite rows of ``people`` (x, y, vx, vy, radius) whose body is within the horizon."""
    rows = np.asarray(people, dtype=np.float64).reshape(-1, 5)
    rows = rows[np.all(np.isfinite(rows), axis=1)]
    rows[:, 4] = np.maximum(rows[:, 4], 0.0)
    return rows[np.hypot(rows[:, 0] - xy[0], rows[:, 1] - xy[1]) - rows[:, 4] <= horizon_m]


def _near_segments(obstacles: FloatArray, xy: tuple[float, float], horizon_m: float) -> FloatArray:
    """The finite, non-degenerate segments (x1, y1, x2, y2) that come within the horizon."""
    rows = np.asarray(obstacles, dtype=np.float64).reshape(-1, 4)
    rows = rows[np.all(np.isfinite(rows), axis=1)]
    rows = rows[np.hypot(rows[:, 2] - rows[:, 0], rows[:, 3] - rows[:, 1]) > 1e-6]   # a wall needs a direction
    if len(rows) == 0:
        return rows
    return rows[project_on_segments(xy, rows[:, :2], rows[:, 2:]).distance <= horizon_m]


def _wall_discs(segments: FloatArray, xy: tuple[float, float], reach_m: float, radius_m: float) -> FloatArray:
    """Centres of discs of ``radius_m`` every ``2 radius_m`` along the segments, ends included,
    those whose disc comes within ``reach_m`` of ``xy``."""
    centres = []
    for x1, y1, x2, y2 in segments:
        count = int(math.ceil(math.hypot(x2 - x1, y2 - y1) / (2.0 * radius_m))) + 1
        t = np.linspace(0.0, 1.0, count)[:, None]
        centres.append(np.hstack([x1 + t * (x2 - x1), y1 + t * (y2 - y1)]))
    if not centres:
        return np.zeros((0, 2))
    points = np.vstack(centres)
    return points[np.hypot(points[:, 0] - xy[0], points[:, 1] - xy[1]) <= reach_m + radius_m]


def _limit_acceleration(previous: tuple[float, float], wanted: tuple[float, float],
                        max_dv: float) -> tuple[float, float]:
    dvx, dvy = wanted[0] - previous[0], wanted[1] - previous[1]
    norm = math.hypot(dvx, dvy)
    if norm <= max_dv or not math.isfinite(max_dv):
        return wanted
    scale = max(max_dv, 0.0) / norm
    return previous[0] + dvx * scale, previous[1] + dvy * scale


def _same(got: Any, wanted: float | int | bool) -> bool:
    if isinstance(wanted, bool):
        return bool(got) == wanted
    return math.isclose(float(got), float(wanted), rel_tol=1e-5, abs_tol=1e-6)


# ------------------------------------------------------------------------------------------ docs
PARAMS_BY_BEHAVIOUR: dict[str, type[NavgroundParams]] = {
    "ORCA": OrcaParams, "HRVO": HrvoParams, "HL": HlParams, "SocialForce": SocialForceParams}


def parameter_table(params: type[NavgroundParams]) -> str:
    """A markdown table of ``params``' fields: name, default, unit and description with its source.

    For a behaviour's model, only what it adds to or changes in `NavgroundParams` is listed.
    docs/baselines.md holds these tables; a unit test checks that they match the models."""
    base = NavgroundParams.model_fields
    rows = ["| parameter | default | unit | meaning and source |", "|---|---|---|---|"]
    for name, info in params.model_fields.items():
        if params is not NavgroundParams and name in base and base[name].default == info.default:
            continue
        unit = next((u for suffix, u in (("_mps", "m/s"), ("_radps", "rad/s"), ("_rad", "rad"), ("_m", "m"),
                                         ("_s", "s")) if name.endswith(suffix)), "")
        default = info.default
        shown = f"{default:.4g}" if isinstance(default, float) else str(default)
        rows.append(f"| `{name}` | {shown} | {unit} | {info.description or ''} |")
    return "\n".join(rows)
