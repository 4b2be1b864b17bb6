"""Local collision avoidance for people: ORCA (van den Berg et al. 2011) through pyrvo (RVO2).

Why ORCA and not the social force model (measured on this machine, /work/shared/notes/
pedestrians.md and docs/people.md): pysocialforce took 20-100 ms per step for 20 people in a
five-room centre (its wall force samples every wall at 10 points per metre) and let people
clog at doors; pyrvo's C++ RVO2 takes ~0.15 ms per step, gives collision-free velocities and kept
everyone out of the walls.  Group formations and gaze, which ORCA lacks, come from where the
behaviour (crowd.py) sends people.

Agents are everybody the crowd knows: people who walk by themselves (``max_speed`` their walking
speed while walking, 0 while standing, so a standing person is never pushed off their place),
people who follow a script and the robot while it drives (*kinematic*: placed and given their
velocity before each step, put back where the script says after it).  RVO2 keeps positions in
float32; both the live simulator and the offline world step the same way, so they agree bit for bit.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pyrvo
from numpy.typing import NDArray

NEIGHBOUR_DISTANCE_M = 3.0
MAX_NEIGHBOURS = 10
TIME_HORIZON_S = 2.0        # how far ahead people avoid each other
TIME_HORIZON_OBSTACLE_S = 1.0
PARKED = (1.0e4, 1.0e4)     # where an absent agent (the robot while it does not drive) waits


class Orca:
    """One RVO2 simulator: walls and furniture as obstacles, one agent per person plus the robot."""

    def __init__(self, dt_s: float, obstacles: Sequence[Sequence[tuple[float, float]]],
                 radii: Sequence[float], positions: NDArray[np.float64]) -> None:
        self.dt_s = dt_s
        self._obstacles = [list(map(tuple, o)) for o in obstacles]
        self._radii = list(radii)
        self.sim = self._new(positions, np.zeros_like(positions), np.zeros(len(positions)))

    def _new(self, positions: NDArray[np.float64], velocities: NDArray[np.float64],
             max_speeds: NDArray[np.float64]) -> pyrvo.RVOSimulator:
        sim = pyrvo.RVOSimulator()
        sim.set_time_step(self.dt_s)
        sim.set_agent_defaults(NEIGHBOUR_DISTANCE_M, MAX_NEIGHBOURS, TIME_HORIZON_S, TIME_HORIZON_OBSTACLE_S,
                               0.25, 0.0, (0.0, 0.0))
        for (x, y), (vx, vy), radius, speed in zip(positions, velocities, self._radii, max_speeds, strict=True):
            index = sim.add_agent((float(x), float(y)))
            sim.set_agent_radius(index, float(radius))
            sim.set_agent_velocity(index, (float(vx), float(vy)))
            sim.set_agent_max_speed(index, float(speed))
            # An agent that cannot move need not look at its neighbours (the others still see it).
            sim.set_agent_max_neighbors(index, MAX_NEIGHBOURS if speed > 0.0 else 0)
        for polygon in self._obstacles:
            sim.add_obstacle(polygon)
        sim.process_obstacles()
        return sim

    def set_obstacles(self, obstacles: Sequence[Sequence[tuple[float, float]]]) -> None:
        """New obstacles (a door closed or opened): RVO2 cannot edit them, so the simulator is rebuilt
        with every agent's exact (float32) state."""
        n = self.sim.get_num_agents()
        positions = np.array([self.sim.get_agent_position(i).to_tuple() for i in range(n)])
        velocities = np.array([self.sim.get_agent_velocity(i).to_tuple() for i in range(n)])
        speeds = np.array([self.sim.get_agent_max_speed(i) for i in range(n)])
        self._obstacles = [list(map(tuple, o)) for o in obstacles]
        self.sim = self._new(positions, velocities, speeds)

    def clone(self) -> Orca:
        """An independent simulator with the same obstacles and agents (positions, velocities and
        speed limits are all of an RVO2 agent's state that survives a step)."""
        n = self.sim.get_num_agents()
        twin = Orca.__new__(Orca)
        twin.dt_s, twin._obstacles, twin._radii = self.dt_s, list(self._obstacles), list(self._radii)
        positions = np.array([self.sim.get_agent_position(i).to_tuple() for i in range(n)]).reshape(n, 2)
        velocities = np.array([self.sim.get_agent_velocity(i).to_tuple() for i in range(n)]).reshape(n, 2)
        speeds = np.array([self.sim.get_agent_max_speed(i) for i in range(n)])
        twin.sim = twin._new(positions, velocities, speeds)
        return twin

    def place(self, index: int, x: float, y: float, vx: float = 0.0, vy: float = 0.0) -> None:
        self.sim.set_agent_position(index, (float(x), float(y)))
        self.sim.set_agent_velocity(index, (float(vx), float(vy)))

    def set_max_speed(self, index: int, speed: float) -> None:
        """0 makes the agent an obstacle the others avoid; it then skips its own avoidance (cheaper)."""
        self.sim.set_agent_max_speed(index, float(speed))
        self.sim.set_agent_max_neighbors(index, MAX_NEIGHBOURS if speed > 0.0 else 0)

    def prefer(self, index: int, vx: float, vy: float) -> None:
        self.sim.set_agent_pref_velocity(index, (float(vx), float(vy)))

    def step(self) -> None:
        self.sim.do_step()

    def position(self, index: int) -> tuple[float, float]:
        return self.sim.get_agent_position(index).to_tuple()

    def velocity(self, index: int) -> tuple[float, float]:
        return self.sim.get_agent_velocity(index).to_tuple()
