import sys

from agents.ros_bridge.agent import RosBridgeAgent
from agents.runtime.base import run_agent

sys.exit(run_agent(RosBridgeAgent))
