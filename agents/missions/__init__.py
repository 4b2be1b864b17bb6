"""Mission planning: mission strings -> symbolic plans (the grammar) -> steps with goal poses.

A library shared by the executive agent (which executes the steps live) and `chronav plan`
(which prints them for a scene at a time), so both plan a mission the same way:
``kinds`` reads the six mission strings, ``planning`` plans them and groups steps into
intentions, ``steps`` resolves each step on the DSR (goal pose, wait, divergence), ``goals`` picks
polite poses, ``preview`` resolves a whole plan offline.
"""
