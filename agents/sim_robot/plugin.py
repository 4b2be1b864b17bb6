"""The sim_robot agent, registered in chronav's pyproject.toml (``chronav.agents``) as a plug-in's would be."""

from __future__ import annotations

from agents.lib.agent_plugins import AgentSpec


def describe() -> AgentSpec:
    """The simulated robot: body, laser, people, world and the sim clock."""
    return AgentSpec(name="sim_robot", process="agents.sim_robot",
                     agent_class="agents.sim_robot.agent:SimRobotAgent",
                     round_order=0, lockstep_options=("busy_rate=0", "perception_lockstep=1"), perceiver=False)
