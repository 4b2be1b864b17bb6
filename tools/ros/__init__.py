"""ROS 2 facing commands: `chronav ros bridge` against a running system and `chronav export` of a run as MCAP."""
