"""Recognises objects and their interaction spaces (python -m agents.object_recognition)."""
