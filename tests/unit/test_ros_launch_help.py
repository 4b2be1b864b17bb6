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
