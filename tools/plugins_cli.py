"""`chronav plugins [--json]`: every installed extension, its kind, name, package, version, what
it does, and whether it loads.

Why a command: a researcher who installed a package of planners wants to see chronav find them
(and why one is refused) before starting a study; the same loaders the runs use check each entry
(agents/lib/registry.py and each kind's module), so "ok" here means a run can use it.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any

import typer


def _loaders() -> dict[str, Callable[[str], Any]]:
    """Each kind's loader: builds the extension as a run does (controllers for a generic robot)."""
    from agents.lib.control.controllers import controller
    from agents.lib.control.protocol import RobotLimits
    from agents.lib.metrics.registered import metric
    from agents.lib.planning.planners import planner
    from agents.lib.socialmap.predictors import predictor

    generic = RobotLimits(radius_m=0.3, max_speed_mps=0.6, max_angular_speed_radps=1.2)
    return {"planner": planner, "controller": lambda name: controller(name, generic), "predictor": predictor,
            "metric": metric, "agent": _agent}


def _agent(name: str) -> Any:
    """An agent's description, checked as a run checks it: its shape, then what it declares it
    writes against the vocabulary (a refusal there is raised as the loaders' refusals are)."""
    from agents.lib.agent_plugins import spec
    from agents.world.vocabulary import vocabulary

    found = spec(name)
    for refusal in vocabulary().refused:
        if refusal.name == name:
            raise refusal
    return found


def inventory() -> list[dict[str, Any]]:
    """One row per registered entry (every kind, sorted by kind then name)."""
    from agents.lib import registry

    loaders = _loaders()
    rows = []
    for kind in registry.GROUPS:
        for name, ext in registry.extensions(kind).items():
            row: dict[str, Any] = {"kind": kind, "name": name, "package": ext.package, "version": ext.version,
                                   "target": ext.target, "group": registry.GROUPS[kind], "summary": "",
                                   "status": "ok", "reason": None}
            try:
                loaders[kind](name)
                row["summary"] = registry.summary(registry.load(kind, name))
            except registry.RefusedExtension as exc:
                row["status"], row["reason"] = "refused", exc.reason
            rows.append(row)
        for ext in registry.shadowed(kind):
            rows.append({"kind": kind, "name": ext.name, "package": ext.package, "version": ext.version,
                         "target": ext.target, "group": registry.GROUPS[kind], "summary": "", "status": "refused",
                         "reason": f"the name is taken by package {registry.entry(kind, ext.name).package!r}"})
    return rows


def register(app: typer.Typer) -> None:
    @app.command("plugins")
    def plugins(as_json: bool = typer.Option(False, "--json", help="one JSON object on stdout")) -> None:
        """List every installed planner, controller, predictor, metric and agent (chronav's and other
        packages'), with its package, version and what it does; refused ones say why."""
        rows = inventory()
        refused = [r for r in rows if r["status"] != "ok"]
        for row in refused:
            typer.echo(f"warning: {row['kind']} plug-in {row['name']!r} from package {row['package']!r} refused: "
                       f"{row['reason']}", err=True)
        if as_json:
            typer.echo(json.dumps({"plugins": rows, "refused": len(refused)}))
            return
        from rich.console import Console
        from rich.table import Table

        from tools.plain import console_width, is_plain, print_lines, wrapped

        console = Console()
        if is_plain(console):    # piped: one line per plug-in, its description wrapped between words
            width = console_width(console)
            lines = ["chronav plug-ins (docs/extending.md): kind name (package version): what it does"]
            for row in rows:
                what = row["summary"] if row["status"] == "ok" else f"REFUSED: {row['reason']}"
                lines += wrapped(f"{row['kind']} {row['name']} ({row['package']} {row['version']}): {what}",
                                 width, indent="    ")
            print_lines(console, lines)
            return
        table = Table(title="chronav plug-ins (docs/extending.md)")
        for column in ("kind", "name", "package", "version", "what it does"):
            table.add_column(column)
        for row in rows:
            what = row["summary"] if row["status"] == "ok" else f"REFUSED: {row['reason']}"
            table.add_row(row["kind"], row["name"], row["package"], row["version"], what)
        console.print(table)
