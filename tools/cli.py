"""The single `chronav` console script.

Why one module per command group: each group imports its heavy dependencies (numba, zenoh, rerun)
only inside its commands, so `chronav --help` stays fast.  Every module listed in COMMAND_MODULES
exposes ``register(app)``; the list is explicit (no discovery by name) so a typo fails loudly.
"""

from __future__ import annotations

import importlib

import typer

COMMAND_MODULES: tuple[str, ...] = (
    "tools.dsr_dump",      # chronav dsr dump
    "tools.scene_cli",     # chronav scene check
    "tools.nav_cli",       # chronav path / chronav metrics
    "tools.grammar_cli",   # chronav grammar check / chronav plan
    "tools.agenda",        # chronav agenda ...
    "tools.launch",        # chronav launch / chronav demo
    "tools.chaos",         # chronav chaos (fault injection)
    "tools.map_cli",       # chronav map export / chronav scene from-map (after tools.scene_cli)
    "tools.evaluate",      # chronav evaluate (planner studies)
)

app = typer.Typer(help="chronav: agenda-aware social navigation on a replicated DSR graph.",
                  no_args_is_help=True, add_completion=False,
                  pretty_exceptions_enable=False)


def _register_all() -> None:
    for module_name in COMMAND_MODULES:
        importlib.import_module(module_name).register(app)


_register_all()


def main() -> None:
    app()


if __name__ == "__main__":
    main()
