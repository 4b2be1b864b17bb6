"""Everything chronav draws in Rerun, in one package: the map, bodies, the DSR graph, the layout.

Why one place: algorithms return data and agents decide *when* to log; *how* a thing looks in the
viewer (entity paths, colours, archetypes) is decided here only, so the recording stays
consistent across the six agent processes and the launcher.  Every function takes a
``agents.runtime.recording.Recorder`` and does nothing when it is disabled.
"""
