"""A scene's agents on one in-memory DSR graph, ticked by the caller: the offline-agents harness.

Why: the agents' DSR contract (who writes which nodes, edges and attributes), the executive's
plans and the navigation's drives can be checked in milliseconds without processes or Zenoh, and
every such test needs the same thing: every agent of a scene built as its process builds it, on
one graph, stepped in an order the test chooses.  py_trees' ``tick_tree`` is the model: one object
builds the tree once, and a test only says which ticks happen.

How: the agents are built as ``chronav launch --in-process`` builds them
(``tools.inprocess.build_agents``: the ``AgentConfig`` a process parses) and set up and stepped by
its scheduler (``agents.runtime.lockstep.Lockstep``: each agent writes as itself, the graph's
signals are delivered after every step, and the wall clock the agents pace by is the scheduler's
virtual one, one period per tick).  Only who steps when is the caller's.  Lives in the tools layer
because it builds agent processes (import-linter: tools > agents > runtime).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path
from types import TracebackType
from typing import Any

from agents.runtime.lockstep import Lockstep
from agents.runtime.recording import Recorder
from dsr import DSRGraph
from scenes.clock import parse_clock
from scenes.loader import resolve_scene_path
from agents.world.vocabulary import vocabulary
from tools.inprocess import build_agents

#: every registered agent, in the order a round steps them
ROUND_ORDER: tuple[str, ...] = vocabulary().names
#: the agents that perceive a tick (their registrations say ``perceiver``), in the order a round
#: steps them (the agenda before the observer: the observer's links follow the agenda)
PERCEIVERS: tuple[str, ...] = tuple(spec.name for spec in vocabulary().agents if spec.perceiver)
#: everything but the social navigation: a test then plays the navigation's part
WITHOUT_NAVIGATION: tuple[str, ...] = tuple(name for name in ROUND_ORDER if name != "social_navigation")


def _time_s(t: str | float) -> float:
    return parse_clock(t) if isinstance(t, str) else float(t)


class OfflineAgents:
    """``agents`` of ``scene`` (names; round order) set up on one graph, none stepped yet.

    ``options`` gives an agent its ``-o KEY=VALUE`` options by name (the observer's ``seed``,
    ``noise_xy``, ...)."""

    def __init__(self, scene: str | Path, run_dir: Path | None = None, *, agents: Iterable[str] = ROUND_ORDER,
                 options: Mapping[str, Mapping[str, str]] | None = None, writer: str = "offline") -> None:
        wanted = set(agents)
        unknown = wanted - set(ROUND_ORDER)
        if unknown:
            raise ValueError(f"no such agent {sorted(unknown)}: the agents are {', '.join(ROUND_ORDER)}")
        self.scene = resolve_scene_path(scene)
        self.run_dir = run_dir
        self.graph = DSRGraph(agent=writer)
        names = [name for name in ROUND_ORDER if name in wanted]
        built = build_agents(self.scene, names, run_dir=run_dir, options=options)
        self.agents: dict[str, Any] = dict(zip(names, built, strict=True))
        self.lockstep = Lockstep(self.graph, built, [Recorder(name, None, None) for name in names])
        self.lockstep.setup()

    def __getitem__(self, name: str) -> Any:
        return self.agents[name]

    @property
    def sim(self) -> Any:
        """The simulator agent (the clock, the robot, the people)."""
        return self.agents["sim_robot"]

    def tick(self, *names: str) -> None:
        """One round: the named agents (all, in round order, when none is named) step once each, in
        that order, the graph's signals delivered after each; the virtual wall clock moves a period."""
        self.lockstep.round([self.agents[name] for name in names] if names else None)

    def skip_to(self, t: str | float) -> None:
        """The simulator jumps to ``t`` (``HH:MM[:SS]`` or seconds): clock, robot and people in one delta."""
        self.sim.skip_to(_time_s(t))
        self.graph.dispatch()

    def at(self, t: str | float) -> None:
        """The clock at ``t``, then every perceiving agent sees that tick (as they do live)."""
        self.skip_to(t)
        self.tick(*(name for name in PERCEIVERS if name in self.agents))

    def settle(self, *names: str, rounds: int = 6) -> None:
        """Tick the named agents until the graph stops changing (live, they run concurrently);
        RuntimeError when it still changes after ``rounds`` rounds."""
        for _ in range(rounds):
            before = self.graph.digest()
            self.tick(*names)
            if self.graph.digest() == before:
                return
        raise RuntimeError(f"the agents {names or ROUND_ORDER} did not settle in {rounds} rounds")

    def add(self, name: str, **options: str) -> Any:
        """Agent ``name`` joins now, set up on the graph as it is (not stepped yet); it is returned."""
        if name in self.agents:
            raise ValueError(f"agent {name} is already on the graph")
        (agent,) = build_agents(self.scene, [name], run_dir=self.run_dir, options={name: options})
        self.lockstep.add(agent, Recorder(name, None, None))
        self.agents[name] = agent
        return agent

    def close(self) -> None:
        """Tear every agent down (files closed)."""
        self.lockstep.teardown()

    def __enter__(self) -> OfflineAgents:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()
