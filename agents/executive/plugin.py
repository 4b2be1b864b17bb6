"""The executive agent, registered in chronav's pyproject.toml (``chronav.agents``) as a plug-in's would be."""

from __future__ import annotations

from agents.lib.agent_plugins import AgentSpec


def describe() -> AgentSpec:
    """Turns missions into plans and intentions, and runs them."""
    return AgentSpec(name="executive", process="agents.executive",
                     agent_class="agents.executive.agent:ExecutiveAgent",
                     round_order=40, lockstep_options=("perception_lockstep=1",), perceiver=False)
