"""Missions -> plans -> intentions (python -m agents.executive)."""
