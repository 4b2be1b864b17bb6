"""The agenda agent process (python -m agents.agenda); its library is agents.lib.agenda."""
