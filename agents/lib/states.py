"""State sets that a library computes and the DSR vocabulary publishes: one definition for both.

Why here, a leaf module that imports nothing: ``ActivityState`` is computed by the agenda library
(``agents/lib/agenda``, a low import layer) and travels on the wire as ``activity.state``, which the
vocabulary (``agents/world/vocabulary.py``, a layer above) declares.  The vocabulary is imported
by every agent and every CLI command; importing it from ``agents.lib.agenda`` would load that
package's calendar stack (icalendar, ~0.1 s) into each of them.  So the enum lives below both,
and both re-export it.
"""

from __future__ import annotations

import enum


class ActivityState(enum.StrEnum):
    """Life cycle of an activity; only ``cancelled`` is stored, the others follow from the clock."""

    SCHEDULED = "scheduled"
    UPCOMING = "upcoming"
    RUNNING = "running"
    FINISHED = "finished"
    CANCELLED = "cancelled"
    #: the states of an activity that is over
    ENDED = enum.nonmember((FINISHED, CANCELLED))
