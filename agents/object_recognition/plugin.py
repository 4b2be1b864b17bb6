"""The object_recognition agent, registered in chronav's pyproject.toml (``chronav.agents``) as a plug-in's would be."""

from __future__ import annotations

from agents.lib.agent_plugins import AgentSpec


def describe() -> AgentSpec:
    """Recognises the scene's objects and their interaction spaces."""
    return AgentSpec(name="object_recognition", process="agents.object_recognition",
                     agent_class="agents.object_recognition.agent:ObjectRecognitionAgent",
                     round_order=10, lockstep_options=(), perceiver=True)
