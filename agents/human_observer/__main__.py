import sys

from agents.human_observer.agent import HumanObserverAgent
from agents.runtime.base import run_agent

sys.exit(run_agent(HumanObserverAgent))
