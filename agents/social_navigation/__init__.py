"""The social navigation agent process (python -m agents.social_navigation); the maths is agents.lib.socialmap."""
