import sys

from agents.runtime.base import run_agent
from agents.sim_robot.agent import SimRobotAgent

sys.exit(run_agent(SimRobotAgent))
