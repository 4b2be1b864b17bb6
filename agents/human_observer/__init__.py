"""Perceives and tracks people (python -m agents.human_observer)."""
