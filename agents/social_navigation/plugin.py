"""The social_navigation agent, registered in chronav's pyproject.toml (``chronav.agents``) as a plug-in's would be."""

from __future__ import annotations

from agents.lib.agent_plugins import AgentSpec


def describe() -> AgentSpec:
    """Plans and drives the robot's paths on the time-dependent social map."""
    return AgentSpec(name="social_navigation", process="agents.social_navigation",
                     agent_class="agents.social_navigation.agent:SocialNavigationAgent",
                     round_order=50, lockstep_options=("perception_lockstep=1",), perceiver=False)
