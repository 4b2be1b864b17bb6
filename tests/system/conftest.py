"""Fixtures of the system tests (tests/system/launch_helpers.py)."""

from tests.system.launch_helpers import evaluate_runs

__all__ = ["evaluate_runs"]
