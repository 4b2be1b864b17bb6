import sys

from agents.runtime.base import run_agent
from agents.social_navigation.agent import SocialNavigationAgent

sys.exit(run_agent(SocialNavigationAgent))
