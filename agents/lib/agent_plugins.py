"""Agents as plug-ins: what an entry of the ``chronav.agents`` group describes, and its checks.

Why a description and not the agent class itself: every chronav process reads the list of agents
(the vocabulary takes in what each writes, the write policy grants it, a launch starts each one,
the in-process runner orders them), and most of those processes never run the agent.  So the
entry point names a small factory that returns an ``AgentSpec``: plain data, cheap to import, that
says where the agent's code is (a module to run as a process, a class for in-process runs) and
what it writes.  chronav's own agents register exactly this way (pyproject.toml, one
``agents/<name>/plugin.py`` each), so a researcher's agent sits beside them.

Why here (agents/lib, beside the registry): the vocabulary (agents/world) reads the descriptions,
and the tools read them too; the description names the agent's code as strings, so nothing here
imports an agent process (``agent_class`` imports it when a run needs it).
"""

from __future__ import annotations

import importlib
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from agents.lib import registry

KIND = "agent"
#: attribute value kinds an agent may declare (the DSR's, docs/dsr_wire_format.md)
VALUE_KINDS = ("float", "int", "bool", "str", "floats", "strs")
_NAME = re.compile(r"^[a-z][a-z0-9_]{0,47}$")
_MODULE = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*$")


@dataclass(frozen=True)
class NodeDecl:
    """A node type an agent owns: it alone creates, deletes and sets its attributes.

    ``attrs``: attribute name -> value kind (one of ``VALUE_KINDS``: a float in SI units, a list of
    strings...)."""

    type: str
    attrs: Mapping[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class EdgeDecl:
    """An edge type an agent writes between node types (``src`` -> ``dst``), with its attributes'
    kinds.  The edge type is new, or one of its ends is a node type the agent owns (an ``RT`` pose
    of its own node, say), so it never writes edges between other agents' nodes."""

    type: str
    src: tuple[str, ...]
    dst: tuple[str, ...]
    attrs: Mapping[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class AgentSpec:
    """What chronav needs to know of an agent, all of it plain data.

    - ``name``: the agent's (and its process's) name, as it writes in the DSR;
    - ``process``: the module a launch runs as ``python -m <process>`` (it calls
      ``agents.runtime.base.run_agent`` with the agent class);
    - ``agent_class``: ``"module:Class"``, the ``Agent`` subclass an in-process run builds;
    - ``round_order``: its place in an in-process round (lower first): chronav's own are the
      simulator 0, object recognition 10, agenda 20, human observer 30, executive 40, navigation 50;
      a plug-in that reads what the perceivers saw this tick goes after 30;
    - ``lockstep_options``: ``KEY=VALUE`` options an in-process run (and an evaluate launch) gives
      it, those that take wall time out of a run;
    - ``perceiver``: whether it perceives each tick of the clock (the offline-agents harness steps
      the perceivers when a test moves the clock);
    - ``nodes`` / ``edges``: the node and edge types it writes (it owns them); chronav's own agents
      declare none here, their types being chronav's core vocabulary (agents/world/vocabulary.py).
    """

    name: str
    process: str
    agent_class: str
    round_order: int
    lockstep_options: tuple[str, ...] = ()
    perceiver: bool = False
    nodes: tuple[NodeDecl, ...] = ()
    edges: tuple[EdgeDecl, ...] = ()
    #: what the agent does, one line (``chronav plugins``); the factory's docstring when empty
    summary: str = ""


def check_spec(name: str, spec: AgentSpec) -> None:
    """ValueError saying what is wrong with ``spec`` registered under ``name`` (its shape only; what
    it writes is checked against the vocabulary by agents/world/vocabulary.py)."""
    if spec.name != name:
        raise ValueError(f"its description is named {spec.name!r}, not {name!r} (the entry point's name)")
    if not _NAME.match(name):
        raise ValueError("an agent's name is lower case letters, digits and _ (at most 48), starting with a letter")
    if not _MODULE.match(spec.process):
        raise ValueError(f"process {spec.process!r} is not a module name (python -m <module>)")
    module, sep, attribute = spec.agent_class.partition(":")
    if not sep or not _MODULE.match(module) or not attribute.isidentifier():
        raise ValueError(f"agent_class {spec.agent_class!r} is not 'module:Class'")
    if isinstance(spec.round_order, bool) or not isinstance(spec.round_order, int):
        raise ValueError(f"round_order {spec.round_order!r} is not an integer")
    for option in spec.lockstep_options:
        if not isinstance(option, str) or "=" not in option:
            raise ValueError(f"lockstep option {option!r} is not KEY=VALUE")
    for node in spec.nodes:
        if not isinstance(node, NodeDecl):
            raise ValueError(f"nodes holds a {type(node).__name__}, not a NodeDecl")
        _check_attrs(f"node type {node.type!r}", node.attrs)
    for edge in spec.edges:
        if not isinstance(edge, EdgeDecl):
            raise ValueError(f"edges holds a {type(edge).__name__}, not an EdgeDecl")
        if not edge.src or not edge.dst:
            raise ValueError(f"edge type {edge.type!r} names no source or no destination node type")
        _check_attrs(f"edge type {edge.type!r}", edge.attrs)


def _check_attrs(what: str, attrs: Mapping[str, str]) -> None:
    for key, kind in attrs.items():
        if kind not in VALUE_KINDS:
            raise ValueError(f"{what}: attribute {key!r} has kind {kind!r}; kinds: {', '.join(VALUE_KINDS)}")


def spec(name: str) -> AgentSpec:
    """The checked description of agent ``name``: UnknownExtension, or RefusedExtension naming
    the plug-in, its package and the reason."""
    found: AgentSpec = registry.built_once(KIND, name, AgentSpec, "the fields of an AgentSpec (agents/lib/agent_plugins.py)")
    try:
        check_spec(name, found)
    except ValueError as exc:
        raise registry.RefusedExtension(KIND, name, registry.entry(KIND, name).package, str(exc)) from None
    return found


def specs() -> tuple[list[AgentSpec], list[registry.RefusedExtension]]:
    """Every registered agent that describes itself well, in round order (then by name), and the
    refused ones.  Deterministic: every process with the same packages installed gets the same."""
    good: list[AgentSpec] = []
    refused: list[registry.RefusedExtension] = []
    for name in registry.names(KIND):
        try:
            good.append(spec(name))
        except registry.RefusedExtension as exc:
            refused.append(exc)
    good.sort(key=lambda s: (s.round_order, s.name))
    return good, refused


def package_of(name: str) -> str:
    """The distribution that registers agent ``name``."""
    return registry.entry(KIND, name).package


def is_own(name: str) -> bool:
    """Whether chronav itself registers agent ``name`` (its types are chronav's core vocabulary)."""
    return package_of(name) == registry.OWN_PACKAGE


def agent_class(found: AgentSpec) -> Any:
    """The agent's class (imported now), or RefusedExtension naming the plug-in, its package and why."""
    module, _, attribute = found.agent_class.partition(":")
    try:
        cls = getattr(importlib.import_module(module), attribute)
    except Exception as exc:  # noqa: BLE001 - any import error of a plug-in is its refusal, reported
        raise registry.RefusedExtension(KIND, found.name, package_of(found.name),
                                        f"cannot import {found.agent_class}: {type(exc).__name__}: {exc}") from None
    if getattr(cls, "kind", None) != found.name:
        raise registry.RefusedExtension(KIND, found.name, package_of(found.name),
                                        f"{found.agent_class}.kind is {getattr(cls, 'kind', None)!r}, not {found.name!r}")
    return cls


def process_missing(found: AgentSpec) -> registry.RefusedExtension | None:
    """A refusal when the agent's process module cannot be found (a launch checks before starting)."""
    from importlib.util import find_spec

    try:
        present = find_spec(found.process) is not None
    except ModuleNotFoundError:      # its parent package is missing
        present = False
    except Exception as exc:  # noqa: BLE001 - a failing parent package is the plug-in's refusal
        return registry.RefusedExtension(KIND, found.name, package_of(found.name),
                                         f"cannot find process module {found.process}: {type(exc).__name__}: {exc}")
    if present:
        return None
    return registry.RefusedExtension(KIND, found.name, package_of(found.name),
                                     f"no module {found.process} to run as its process")
