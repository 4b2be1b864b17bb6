"""The agent base class and the loop that runs it as an OS process.

Why the split (after py_trees' Behaviour): an Agent holds the behaviour (``setup``/``step``/
``teardown``) and never opens sessions itself; ``run_agent`` owns the middleware, the loop, the
signals and the cleanup.  That makes every agent constructible offline in a unit test, and makes
shutdown uniform: SIGINT/SIGTERM end the loop, the recording gets its footer, the Zenoh session is
closed (an unclosed session hangs the interpreter at exit).  The loop also stamps the agent's
heartbeat in the DSR (agents/runtime/heartbeat.py), so a launcher can tell a stuck agent from a
busy one.  The graph an agent gets is a ``CheckedGraph`` (agents/runtime/checked_graph.py): a
write outside the vocabulary is refused, logged and counted, never written.  Credentials come
from the environment like every Zenoh setting (``CHRONAV_ZENOH_USER`` +
``CHRONAV_ZENOH_PASSWORD_FILE``, written by the launcher for each run).
"""

from __future__ import annotations

import faulthandler
import logging
import os
import signal
import sys
import threading
import time
from abc import ABC, abstractmethod
from collections.abc import Callable
from typing import ClassVar

from agents.runtime.checked_graph import CheckedGraph
from agents.runtime.config import AgentConfig, parse_agent_args
from agents.runtime.heartbeat import Heartbeat
from agents.runtime.recording import Recorder
from agents.world.scene_world import SceneWorld, load_world
from scenes.model import Scene

log = logging.getLogger("chronav.agent")
#: seconds after a stop signal before a still-running agent logs every thread's stack (the
#: launcher's stop_all SIGKILLs what is left after 8 s)
STOP_TRACE_S = 5.0


class Agent(ABC):
    """One CORTEX agent: reacts to DSR signals and runs ``step`` every loop period."""

    kind: ClassVar[str]
    #: the wall clock an agent paces itself by (rates, watchdogs).  Why a hook: run in-process
    #: (agents/runtime/lockstep.py) the scheduler hands every agent its virtual wall clock, so a
    #: run's pacing, and with it the simulated world, does not depend on how loaded the machine is.
    wall_clock: Callable[[], float] = staticmethod(time.monotonic)
    #: what keeps the agent from its job right now, in a user's words ("" when nothing); stamped on
    #: its heartbeat, so the launcher shows it on the console (agents/runtime/heartbeat.py)
    problem: str = ""

    def __init__(self, config: AgentConfig) -> None:
        self.config = config
        self.world: SceneWorld = load_world(config.scene)
        self.scene: Scene = self.world.scene
        self.log = logging.getLogger(f"chronav.{config.name}")

    @abstractmethod
    def setup(self, graph: CheckedGraph, recorder: Recorder) -> None:
        """Called once the replica has joined: declare signal handlers, write initial nodes.  Run by
        ``run_agent`` or the lockstep scheduler, ``graph`` checks every write against the vocabulary."""

    @abstractmethod
    def step(self) -> None:
        """One iteration of the agent loop (wall period ``config.period_s``)."""

    def teardown(self) -> None:  # noqa: B027 - optional hook: most agents have nothing to release
        """Called once on the way out, still connected."""


def configure_logging(name: str) -> None:
    logging.basicConfig(level=logging.INFO, stream=sys.stderr,
                        format=f"%(asctime)s {name:>17} %(levelname)-7s %(message)s", datefmt="%H:%M:%S")


def stop_on_signals(name: str, trace_after_s: float = STOP_TRACE_S) -> threading.Event:
    """An event set by SIGTERM or SIGINT; the run loop ends when it is set.

    A stop that hangs ends in the launcher's SIGKILL, which leaves no trace of where it hung, so
    after ``trace_after_s`` the stacks of every thread go to stderr (the agent's log)."""
    stop = threading.Event()

    def request_stop(signum: int, _frame: object) -> None:
        log.info("%s received signal %d, stopping", name, signum)
        stop.set()
        faulthandler.dump_traceback_later(trace_after_s, exit=False)

    signal.signal(signal.SIGTERM, request_stop)
    signal.signal(signal.SIGINT, request_stop)
    return stop


def run_agent(agent_cls: type[Agent], argv: list[str] | None = None) -> int:
    """Entry point of ``python -m agents.<kind>``: parse flags, join the DSR, loop until signalled."""
    from dsr import join
    from dsr.collector import FreeMemoryTimer
    from dsr.log_rotation import LogRotation
    from agents.runtime.exit_guard import leave
    from dsr.config import ZenohSettings
    from agents.world.write_policy import policy_from_env

    config = parse_agent_args(agent_cls.kind, argv)
    configure_logging(config.name)
    try:
        # A real-time run's agent cuts its log every hour (dsr/log_rotation.py).
        log_rotation = LogRotation.from_env()
    except ValueError as exc:
        log.error("%s: %s", config.name, exc)
        return 2
    stop = stop_on_signals(config.name)

    # Started by the launcher: if it dies (even by SIGKILL) this agent must not linger as an orphan.
    parent = os.getppid() if os.environ.get("CHRONAV_EXIT_WITH_PARENT") == "1" else None
    agent = agent_cls(config)
    recorder = Recorder(config.name, config.run_dir, config.recording_id, day=agent.scene.clock.date)
    settings = ZenohSettings.from_env()
    policy = policy_from_env()  # agents/world/write_policy.yaml unless CHRONAV_WRITE_POLICY says otherwise
    try:
        with join(agent=config.name, graph=config.graph, settings=settings, policy=policy) as replicated:
            graph = CheckedGraph(replicated, config.name)   # writes outside the vocabulary are refused
            agent.setup(graph, recorder)
            log.info("%s joined graph %r", config.name, config.graph)
            heartbeat = Heartbeat(graph, config.name)
            # An agent lives all day in real time: what its heap frees goes back to the system
            # every minute (dsr/collector.py), or its memory creeps up for good.
            free_memory = FreeMemoryTimer()
            try:
                while not stop.is_set():
                    if parent is not None and os.getppid() != parent:
                        log.warning("%s: launcher (pid %d) is gone, stopping", config.name, parent)
                        break
                    started = time.monotonic()
                    graph.dispatch(timeout=0.0)
                    agent.step()
                    heartbeat.maybe_beat(agent.problem)
                    free_memory.maybe_release()
                    if log_rotation is not None:
                        log_rotation.maybe_rotate()
                    remaining = config.period_s - (time.monotonic() - started)
                    if remaining > 0:
                        # Wait for signals (DSR changes) rather than sleeping blind.
                        graph.dispatch(timeout=remaining)
            finally:
                agent.teardown()
    finally:
        recorder.close()
    faulthandler.cancel_dump_traceback_later()
    log.info("%s stopped", config.name)
    # The session is closed: wait for its threads to leave Zenoh before the interpreter finalises,
    # or a stopped agent can abort ("FATAL: exception not rethrown") and read as a crash.  A few
    # seconds only: the launcher gives all its agents 8 s to stop before it kills them.
    leave(0, grace_s=3.0, what=f"agent {config.name}")
    return 0
