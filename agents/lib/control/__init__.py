"""Local control: what turns the global path into velocity commands, one cycle at a time.

`protocol` says what every local controller is given and returns (units and frames); chronav's
elastic band and the field's established behaviours (navground's ORCA, HRVO, HL, social force)
implement it, and the registry finds them by name.
"""
