"""The agenda agent, registered in chronav's pyproject.toml (``chronav.agents``) as a plug-in's would be."""

from __future__ import annotations

from agents.lib.agent_plugins import AgentSpec


def describe() -> AgentSpec:
    """Runs the agenda: activities, their objects' social cost R(t), staff changes."""
    return AgentSpec(name="agenda", process="agents.agenda",
                     agent_class="agents.agenda.agent:AgendaAgent",
                     round_order=20, lockstep_options=(), perceiver=True)
