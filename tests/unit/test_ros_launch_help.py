"""`chronav launch --robot ros` starts the ROS 2 bridge without `--ros`, and --help and
docs/ros2.md say so (issue 42: the help said it needed --ros)."""

from __future__ import annotations

from typing import Any

import pytest
from typer.testing import CliRunner

from tests.support import REPO_ROOT
from tools.cli import app


def test_robot_ros_starts_the_bridge_without_ros_and_help_and_docs_say_so(monkeypatch: pytest.MonkeyPatch) -> None:
    import tools.system.console as console

    seen: dict[str, Any] = {}

    def fake_run(scene: str, **options: Any) -> int:
        seen.update(options)
        return 0

    monkeypatch.setattr(console, "run_with_progress", fake_run)
    monkeypatch.delenv("ROS_DOMAIN_ID", raising=False)
    result = CliRunner().invoke(app, ["launch", "ros_lounge", "--robot", "ros"])
    assert result.exit_code == 0, result.output
    assert seen["ros_domain"] == 0 and seen["robot"] == "ros"
    monkeypatch.setenv("COLUMNS", "400")   # rich wraps the help in boxes: one line per option
    help_text = " ".join(CliRunner().invoke(app, ["launch", "--help"]).output.replace("│", " ").split())
    assert "--ros not needed" in help_text and "needs --ros" not in help_text
    docs = (REPO_ROOT / "docs" / "ros2.md").read_text(encoding="utf-8")
    assert "`--robot ros` starts the bridge itself: `--ros` is not needed" in docs


def test_a_run_with_ros_goals_ends_at_the_scenes_close_as_docs_ros2_says() -> None:
    """docs/ros2.md: once a ROS goal became a mission, the scene's missions being done does not end
    the run; the scene's close (the clock finished) does, or --timeout."""
    import time
    from types import SimpleNamespace

    from tools.launch import _run_over

    def run(missions: dict[str, dict[str, object]]) -> SimpleNamespace:
        return SimpleNamespace(missions=missions, spec=SimpleNamespace(missions=["deliver"]), interrupted=False,
                               timed_out=False, started=time.monotonic(),
                               supervisor=SimpleNamespace(given_up=lambda: False))

    stop = SimpleNamespace(requested=False)
    scene_only = {"deliver": {"state": "done"}}
    with_ros = {**scene_only, "ros_goal_1": {"state": "done"}}
    assert _run_over(run(scene_only), stop, {"clock_finished": False}, 900.0)
    assert not _run_over(run(with_ros), stop, {"clock_finished": False}, 900.0)
    assert _run_over(run(with_ros), stop, {"clock_finished": True}, 900.0)
    late = run(with_ros)
    late.started -= 1000.0
    assert _run_over(late, stop, {"clock_finished": False}, 900.0) and late.timed_out
    docs = (REPO_ROOT / "docs" / "ros2.md").read_text(encoding="utf-8")
    assert "once a ROS goal became a mission, the run no longer ends when" in docs
