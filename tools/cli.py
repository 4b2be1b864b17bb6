"""The single `chronav` console script.

Why one module per command group: each group imports its heavy dependencies (numba, zenoh, rerun)
only inside its commands, so `chronav --help` stays fast.  Every module listed in COMMAND_MODULES
exposes ``register(app)``; the list is explicit (no discovery by name) so a typo fails loudly.
"""

from __future__ import annotations

import gc
import importlib
import sys

import typer

COMMAND_MODULES: tuple[str, ...] = (
    "tools.system.dsr_dump",      # chronav dsr dump
    "tools.scene.scene_cli",      # chronav scene check
    "tools.plan.nav_cli",         # chronav path / chronav metrics
    "tools.plan.grammar_cli",     # chronav grammar check / chronav plan
    "tools.agenda",               # chronav agenda ...
    "tools.system.launch_cli",    # chronav launch / chronav demo
    "tools.chaos.command",        # chronav chaos (fault injection)
    "tools.scene.map_cli",        # chronav map export / chronav scene from-map (after tools.scene.scene_cli)
    "tools.evaluate.command",     # chronav evaluate (planner studies)
    "tools.ros.export_cli",       # chronav export (a run as rosbag2 MCAP)
    "tools.ros.bridge_cli",       # chronav ros bridge (the ROS 2 bridge against a running system)
    "tools.predict_cli",          # chronav predict evaluate (people prediction on real pedestrians)
    "tools.plugins_cli",          # chronav plugins (every installed extension)
    "tools.system.report_cli",    # chronav report (a finished run's per-mission tables)
    "tools.scene.crowd_cli",      # chronav scene from-crowd (recorded pedestrians; after tools.scene.scene_cli)
)

app = typer.Typer(help="chronav: agenda-aware social navigation on a replicated DSR graph.",
                  no_args_is_help=True, add_completion=False,
                  pretty_exceptions_enable=False)


def _register_all() -> None:
    for module_name in COMMAND_MODULES:
        importlib.import_module(module_name).register(app)


_register_all()


# The cyclic collector's thresholds for a CLI process: a collection waits for 250,000 new objects
# instead of Python's 700 (older generations keep their defaults).
GC_THRESHOLDS = (250_000, 10, 10)


def main() -> None:
    """The console script: the typer app, with the collector tuned for a short-lived process.

    Why: an offline command such as `chronav path` imports numba, scipy.linalg and our modules,
    some 150,000 objects that live until the process ends.  With Python's thresholds the cyclic
    collector rescans them hundreds of times while they load, and again at interpreter shutdown
    (a large share of a 1 s command: docs/performance.md).  So a collection waits for 250,000 new objects (such a
    command then runs none), and at the end everything is frozen (``gc.freeze``): shutdown still
    runs the atexit handlers and frees every module, but no longer walks those objects for cycles.
    Long-running commands (launch, demo, chaos) still collect, in larger steps; only cyclic garbage
    waits longer (most objects are freed by reference counting).  The agents are separate processes:
    each raises the thresholds when it opens its replica (dsr/collector.py).  ``tests/unit/test_cli_imports.py`` guards what `chronav path` imports.
    """
    gc.set_threshold(*GC_THRESHOLDS)
    exit_code: object = 1
    try:
        app()
    except SystemExit as exc:
        exit_code = exc.code
        raise
    except Exception as exc:
        # A bad CHRONAV_DSR_* variable that no command caught (the DSR reads its limits when it
        # is first imported): name it, no traceback.  Looked up, not imported, so that `chronav
        # --help` does not load the DSR, and so that a failed import is not retried here.
        errors = sys.modules.get("dsr.errors")
        if errors is None or not isinstance(exc, errors.ConfigError):
            raise
        typer.echo(f"chronav: {exc}; fix or unset that environment variable", err=True)
        exit_code = 2
        raise SystemExit(2) from None
    finally:
        # no daemon thread may be in Zenoh's or Rerun's native code at finalisation (its abort
        # is "FATAL: exception not rethrown"): agents/runtime/exit_guard.py
        from agents.runtime.exit_guard import leave
        leave(exit_code)
        gc.freeze()


if __name__ == "__main__":
    main()
