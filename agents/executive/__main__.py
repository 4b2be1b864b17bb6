import sys

from agents.executive.agent import ExecutiveAgent
from agents.runtime.base import run_agent

sys.exit(run_agent(ExecutiveAgent))
