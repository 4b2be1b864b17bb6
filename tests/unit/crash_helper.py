"""A stand-in process for supervisor tests: exits with a code, or sleeps."""

import argparse
import sys
import time

parser = argparse.ArgumentParser()
parser.add_argument("--exit", type=int, default=None)
parser.add_argument("--sleep", type=float, default=0.0)
args = parser.parse_args()
time.sleep(args.sleep)
sys.exit(args.exit or 0)
