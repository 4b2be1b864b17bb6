"""Local controllers by name: chronav's elastic band and any installed package's, through the
``chronav.controllers`` entry points (chronav registers its own there, as an outside package does).

An entry point names a FACTORY ``factory(limits: RobotLimits) -> LocalController`` (protocol.py);
the navigation agent builds one per run and calls ``reset``/``command``.  Its answers are checked
(``checked``): a command that is not a ControlCommand of finite numbers is refused
(ControllerFailed names the controller and its package) and the agent stops the robot.
"""

from __future__ import annotations

import math
from typing import Any

from agents.lib import registry
from agents.lib.control.protocol import ControlCommand, LocalController, RobotLimits

DEFAULT_CONTROLLER = "elastic_band"


class ControllerFailed(RuntimeError):
    """A controller raised, or answered something that is not a finite ControlCommand."""

    def __init__(self, name: str, reason: str) -> None:
        found = registry.extensions("controller").get(name)
        where = f" from package {found.package!r}" if found is not None else ""
        super().__init__(f"controller {name!r}{where} failed: {reason}")
        self.name, self.reason = name, reason


def controller_names() -> tuple[str, ...]:
    """Every installed controller's name (entry point metadata only: imports nothing)."""
    return registry.names("controller")


def factory(name: str) -> Any:
    """The factory ``name`` registers, imported once (UnknownExtension, RefusedExtension)."""
    return registry.load("controller", name, registry.check_callable)


def controller(name: str, limits: RobotLimits) -> LocalController:
    """A new controller ``name`` for a robot with ``limits``; RefusedExtension when its factory
    fails or builds something without reset() and command()."""
    return registry.build("controller", name, LocalController, "reset() and command()", limits)


def checked(answer: object, name: str) -> ControlCommand:
    """``answer`` if it is a ControlCommand of finite numbers, else ControllerFailed."""
    if not isinstance(answer, ControlCommand):
        raise ControllerFailed(name, f"returned a {type(answer).__name__}, not a ControlCommand")
    values = {"vx": answer.vx, "vy": answer.vy, "omega": answer.omega}
    for key, value in values.items():
        if not isinstance(value, (int, float)) or not math.isfinite(value):
            raise ControllerFailed(name, f"returned {key} = {value!r} (NaN or infinite commands are refused)")
    return answer


def command(chosen: LocalController, name: str, control_input: Any) -> ControlCommand:
    """One checked cycle of ``chosen``: its exceptions and bad answers become ControllerFailed."""
    try:
        answer = chosen.command(control_input)
    except Exception as exc:
        raise ControllerFailed(name, f"raised {type(exc).__name__}: {exc}") from exc
    return checked(answer, name)
