"""docs/baselines.md lists each navground behaviour's parameters exactly as the models define them."""

from __future__ import annotations

from pathlib import Path

import pytest

from agents.lib.control.navground_behaviours import PARAMS_BY_BEHAVIOUR, NavgroundParams, parameter_table

DOC = Path(__file__).resolve().parents[2] / "docs" / "baselines.md"


@pytest.mark.parametrize("params", [NavgroundParams, *PARAMS_BY_BEHAVIOUR.values()], ids=lambda p: p.__name__)
def test_the_parameter_tables_match_the_models(params: type[NavgroundParams]) -> None:
    text = DOC.read_text(encoding="utf-8")
    assert "## The behaviours and their parameters" in text
    assert f"(`{params.__name__}`)" in text
    assert parameter_table(params) in text, (
        f"docs/baselines.md: the table of {params.__name__} is out of date; regenerate it with "
        f"agents.lib.control.navground_behaviours.parameter_table")


def test_every_parameter_names_its_source() -> None:
    models: list[type[NavgroundParams]] = [NavgroundParams, *PARAMS_BY_BEHAVIOUR.values()]
    for params in models:
        for name, info in params.model_fields.items():
            assert info.description, f"{params.__name__}.{name} has no description"
            assert any(word in info.description for word in ("navground", "paper", "chronav", "RVO2", "HRVO")), \
                f"{params.__name__}.{name}: the description does not say where the default comes from"
