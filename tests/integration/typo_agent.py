"""A simulator with the vocabulary's own example typo, run as a real agent process.

``python -m tests.integration.typo_agent --scene S -o status=FILE`` runs through ``run_agent``
(agents/runtime/base.py) exactly like ``python -m agents.sim_robot``: it joins the graph over Zenoh
with the shipped write policy and gets the runtime's checked graph.  It writes the clock as the
simulator does, ticking ``now_s``; on its 5th step it writes ``now_S`` instead (the typo), then goes
on ticking until step 20.  Its status file says how far it got and what its graph refused
(tests/integration/test_vocabulary_live.py).
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path
from typing import Any

from agents.runtime.base import Agent, run_agent
from agents.runtime.recording import Recorder
from agents.world.vocabulary import CLOCK, ClockAttr, ClockMode, NodeType

TYPO_STEP, LAST_STEP = 5, 20


class TypoClockAgent(Agent):
    kind = "sim_robot"

    def setup(self, graph: Any, recorder: Recorder) -> None:
        self.graph = graph
        self.steps = 0
        self.status = Path(self.config.option("status", "typo_agent.json"))
        graph.insert_node(NodeType.CLOCK, CLOCK, {ClockAttr.NOW_S: 0.0, ClockAttr.MODE: ClockMode.IDLE})

    def step(self) -> None:
        if self.steps >= LAST_STEP:
            return
        self.steps += 1
        clock = self.graph.get_node_by_name(CLOCK)
        key = "now_S" if self.steps == TYPO_STEP else ClockAttr.NOW_S
        self.graph.update_node(clock.id, {key: float(self.steps)})
        status = {"steps": self.steps, "refused": self.graph.refused, "last_refusal": self.graph.last_refusal,
                  "clock": dict(self.graph.get_node_by_name(CLOCK).attrs)}
        tmp = self.status.with_suffix(".tmp")
        tmp.write_text(json.dumps(status))
        os.replace(tmp, self.status)


if __name__ == "__main__":
    sys.exit(run_agent(TypoClockAgent))
