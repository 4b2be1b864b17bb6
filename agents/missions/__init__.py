"""Mission planning: mission strings -> symbolic plans (the grammar) -> steps with goal poses.

A library shared by the executive agent (which executes the steps live) and `chronav plan`
(which prints them for a scene at a time), so both plan a mission the same way.
"""
