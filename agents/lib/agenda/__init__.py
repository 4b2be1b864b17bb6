"""The centre's agenda: activities staff write (YAML or iCalendar), expanded for one sim day.

Pipeline (one module per step): ``yaml_source`` / ``ics_source`` read files -> ``expand`` places
the activities on a date in the centre's time zone -> ``validate`` checks them against the scene
-> ``changes`` applies runtime edits.  ``chronemics`` gives each object's R(t)
from ``AgendaDay.windows()``.
"""

from agents.lib.agenda.changes import (AddChange, AgendaChange, AgendaChangeError, CancelChange, LoadChange,
                                   MoveChange, add_activity, apply_change, cancel_activity,
                                   load_activities, move_activity, parse_change)
from agents.lib.agenda.expand import AgendaSource, derive_id, expand_day
from agents.lib.agenda.ics_source import IcsAgenda, load_ics_file, parse_ics
from agents.lib.agenda.model import (Activity, ActivitySpec, ActivityState, ActivityWindow, AgendaDay,
                                 AgendaError, AgendaSourceError, UnknownActivityError,
                                 activity_state)
from agents.lib.agenda.validate import (AgendaValidationError, Finding, Severity, ValidationReport,
                                    validate_activities, validate_day)
from agents.lib.agenda.yaml_source import (load_agenda_file, load_scene_agenda, load_yaml_file,
                                       parse_agenda_text, parse_yaml_agenda)

__all__ = [
    "Activity", "ActivitySpec", "ActivityState", "ActivityWindow", "AddChange", "AgendaChange",
    "AgendaChangeError", "AgendaDay", "AgendaError", "AgendaSource", "AgendaSourceError",
    "AgendaValidationError", "CancelChange", "Finding", "IcsAgenda", "LoadChange", "MoveChange",
    "Severity", "UnknownActivityError", "ValidationReport", "activity_state",
    "add_activity", "apply_change", "cancel_activity", "derive_id", "expand_day",
    "load_activities", "load_agenda_file", "load_ics_file", "load_scene_agenda", "load_yaml_file",
    "move_activity", "parse_agenda_text", "parse_change", "parse_ics",
    "parse_yaml_agenda", "validate_activities", "validate_day",
]
