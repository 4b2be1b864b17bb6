"""``--model FILE`` of launch, evaluate and predict evaluate: a walker model file checked where the
user gave it, then handed to the human observer through its config (``-o walker_model=PATH``).

Why checked here: an agent that cannot read its model would fail inside a run (a process restarted
three times, a lockstep error); a bad file named with its key before anything starts is the error
a person can act on."""

from __future__ import annotations

from pathlib import Path

import typer


def checked_model(model: Path | None, option: str = "--model") -> Path | None:
    """The model file, absolute, after loading it once (walker_model.load's checks)."""
    if model is None:
        return None
    from agents.lib.perception.walker_model import WalkerModelError, load

    try:
        load(model)
    except WalkerModelError as exc:
        raise typer.BadParameter(str(exc), param_hint=option) from None
    return model.resolve()


def model_options(model: Path | None) -> dict[str, list[str]] | None:
    """The observer's ``-o`` option for ``model`` (None: the shipped model)."""
    path = checked_model(model)
    return None if path is None else {"human_observer": [f"walker_model={path}"]}
