import sys

from agents.agenda.agent import AgendaAgent
from agents.runtime.base import run_agent

sys.exit(run_agent(AgendaAgent))
