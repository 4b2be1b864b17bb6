"""The human_observer agent, registered in chronav's pyproject.toml (``chronav.agents``) as a plug-in's would be."""

from __future__ import annotations

from agents.lib.agent_plugins import AgentSpec


def describe() -> AgentSpec:
    """Perceives and tracks people, their rooms and interactions."""
    return AgentSpec(name="human_observer", process="agents.human_observer",
                     agent_class="agents.human_observer.agent:HumanObserverAgent",
                     round_order=30, lockstep_options=("perception_lockstep=1",), perceiver=True)
