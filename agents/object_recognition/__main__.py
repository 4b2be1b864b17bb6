import sys

from agents.object_recognition.agent import ObjectRecognitionAgent
from agents.runtime.base import run_agent

sys.exit(run_agent(ObjectRecognitionAgent))
