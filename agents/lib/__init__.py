"""Libraries shared by the agent processes and the tools: pure code, no process, no Rerun, no Zenoh session."""
