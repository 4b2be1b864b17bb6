"""Every agent of a run in one process, on one DSR graph, stepped in lockstep by one scheduler.

Why: a launch is seven processes (router, six agents) that each import chronav, compile their
kernels, join the graph through Zenoh and then wait on each other in lockstep anyway: on a small
scene that start-up and hand-shaking is most of the run.  A planner study of a thousand runs
wants the same agents, the same graph vocabulary and the same clock, without the processes.  And
the processes interleave as the machine's load decides; one scheduler stepping the agents in a
fixed order makes a run a function of its scene, options and seed alone.

How: the agents are built exactly as ``run_agent`` builds them (their ``setup`` gets the graph and
a recorder), on ONE offline ``dsr.DSRGraph`` (one replica, no transport).  A *round* steps every
agent once, in the launch's data-flow order (the simulator publishes the clock, the perceivers see
that tick, the executive and the navigation act on it), and delivers the graph's signals after each
agent, as a replica's ``dispatch`` would.  Each agent keeps its own sim-time periods (the
navigation replans every 0.2 s of sim time, object recognition looks every 5 s, the observer at
every tick); the simulator advances the clock by at most one control step per round, and only
when the navigation answered the pose, so a round is one tick of sim time while driving.
Whatever an agent paces by the wall clock (the simulator's rates and watchdogs) reads the
scheduler's *virtual* wall clock (``Agent.wall_clock``), which advances ``period_s`` per round:
no run depends on how fast this machine is.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from agents.lib.agent_plugins import package_of
from agents.lib.registry import OWN_PACKAGE, UnknownExtension
from agents.runtime.base import Agent
from agents.runtime.checked_graph import CheckedGraph
from agents.runtime.recording import Recorder

if TYPE_CHECKING:   # the scheduler drives the concrete graph: its dispatch loop and local write policy
    from dsr import DSRGraph

log = logging.getLogger("chronav.lockstep")
#: virtual wall seconds per round: the period every agent process loops at
ROUND_PERIOD_S = 0.02
#: rounds in which nothing changes in the graph before the run is declared stalled
STALL_ROUNDS = 20_000


class VirtualClock:
    """A wall clock that moves only when the scheduler moves it (``Agent.wall_clock``)."""

    def __init__(self, start_s: float = 0.0) -> None:
        self.now_s = start_s

    def __call__(self) -> float:
        return self.now_s

    def advance(self, dt_s: float) -> None:
        self.now_s += dt_s


class AgentError(RuntimeError):
    """An agent raised inside its ``setup`` or ``step``: the run cannot go on (no supervisor here)."""

    def __init__(self, agent: str, exc: BaseException) -> None:
        super().__init__(f"agent {agent} failed: {type(exc).__name__}: {exc}")
        self.agent = agent


@dataclass
class LockstepOutcome:
    """How ``Lockstep.run`` ended: ``reason`` is done, interrupted, timed_out or stalled."""

    reason: str
    rounds: int
    wall_s: float


class Lockstep:
    """The scheduler: ``setup`` the agents on ``graph``, then ``run`` rounds until ``done()``."""

    def __init__(self, graph: DSRGraph, agents: Sequence[Agent], recorders: Sequence[Recorder], *,
                 period_s: float = ROUND_PERIOD_S, policy: Any = None) -> None:
        """``policy``: the write policy a launch's replicas enforce (agents/world/write_policy.py);
        each agent's writes are then checked under its own name, as its replica would check them."""
        if len(agents) != len(recorders):
            raise ValueError("one recorder per agent")
        self.graph = graph
        if policy is not None:
            graph.local_policy = policy
        self.agents = list(agents)
        self.recorders = list(recorders)
        self.period_s = period_s
        self.clock = VirtualClock()
        self.rounds = 0
        self._set_up: list[Agent] = []
        #: agent plug-ins that raised and left the run: name -> what happened (plug-in, package, error)
        self.dropped: dict[str, str] = {}

    def setup(self) -> None:
        """Set every agent up in order (the simulator first: it writes the building and the clock)."""
        for agent, recorder in list(zip(self.agents, self.recorders, strict=True)):   # a plug-in may leave
            self._set_up_one(agent, recorder)

    def add(self, agent: Agent, recorder: Recorder) -> None:
        """One more agent joins the run now (set up on the graph as it is), stepped after the others."""
        self.agents.append(agent)
        self.recorders.append(recorder)
        self._set_up_one(agent, recorder)

    def _set_up_one(self, agent: Agent, recorder: Recorder) -> None:
        agent.wall_clock = self.clock
        try:
            with self._as(agent):
                agent.setup(CheckedGraph(self.graph, agent.config.name), recorder)
        except Exception as exc:
            if not self._drop_plugin(agent, exc, "setup"):
                raise AgentError(agent.config.name, exc) from exc
            return
        self._set_up.append(agent)
        self.graph.dispatch()

    def round(self, agents: Sequence[Agent] | None = None) -> None:
        """One tick: every agent (or ``agents``, in that order) steps once, the graph's signals
        delivered after each; then the virtual wall clock moves one period."""
        for agent in list(self.agents) if agents is None else agents:
            self.step(agent)
        self.clock.advance(self.period_s)
        self.rounds += 1

    def step(self, agent: Agent) -> None:
        """``agent`` steps once (writing as itself) and the graph's signals are delivered."""
        if agent.config.name in self.dropped:
            return
        try:
            with self._as(agent):
                agent.step()
        except Exception as exc:
            if not self._drop_plugin(agent, exc, "step"):
                raise AgentError(agent.config.name, exc) from exc
        self.graph.dispatch()

    def _drop_plugin(self, agent: Agent, exc: Exception, where: str) -> bool:
        """Whether ``agent`` is an outside package's agent plug-in, now out of the run: one that raises
        is logged (naming it, its package and the error) and the others go on, as a launch goes on
        without a plug-in it refused at start.  chronav's own agents' errors end the run (False)."""
        name = agent.config.name
        try:
            package = package_of(name)
        except UnknownExtension:       # built outside the registry (a test's agent): as chronav's own
            return False
        if package == OWN_PACKAGE:
            return False
        self.dropped[name] = (f"agent plug-in {name!r} from package {package!r} failed in {where}: "
                              f"{type(exc).__name__}: {exc}; it left the run, the others go on")
        log.warning("%s", self.dropped[name])
        if agent in self.agents:
            self.agents.remove(agent)
        self.graph.dispatch()
        return True

    @contextmanager
    def _as(self, agent: Agent) -> Iterator[None]:
        """The graph writes as ``agent`` meanwhile (one replica, one writer name at a time): what the
        write policy checks, and what a launch's replica of that agent would write as."""
        graph, previous = self.graph, self.graph.agent
        graph.agent = agent.config.name
        try:
            yield
        finally:
            graph.agent = previous

    def run(self, done: Callable[[], bool], *, timeout_s: float = float("inf"),
            stop: threading.Event | None = None, on_round: Callable[[int], None] | None = None,
            stall_rounds: int = STALL_ROUNDS) -> LockstepOutcome:
        """Rounds until ``done()`` (checked after each), the wall ``timeout_s``, ``stop`` being set
        or Ctrl-C, or ``stall_rounds`` rounds in which the graph did not change (agents waiting on
        each other for ever: a bug, reported instead of spinning)."""
        started = time.monotonic()
        quiet, last_version = 0, self.graph.version
        try:
            while True:
                self.round()
                if on_round is not None:
                    on_round(self.rounds)
                if done():
                    return LockstepOutcome("done", self.rounds, time.monotonic() - started)
                version = self.graph.version
                quiet = quiet + 1 if version == last_version else 0
                last_version = version
                if quiet >= stall_rounds:
                    return LockstepOutcome("stalled", self.rounds, time.monotonic() - started)
                if stop is not None and stop.is_set():
                    return LockstepOutcome("interrupted", self.rounds, time.monotonic() - started)
                if time.monotonic() - started > timeout_s:
                    return LockstepOutcome("timed_out", self.rounds, time.monotonic() - started)
        except KeyboardInterrupt:
            return LockstepOutcome("interrupted", self.rounds, time.monotonic() - started)

    def teardown(self) -> None:
        """Every agent that was set up is torn down (files closed), then the recorders closed."""
        for agent in reversed(self._set_up):
            try:
                agent.teardown()
            except Exception:  # noqa: BLE001 - one agent's teardown must not keep the others' open
                pass
        for recorder in self.recorders:
            recorder.close()
