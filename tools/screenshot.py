"""Render a recording to a PNG at a given sim time, headless (for docs, reviews and CI artefacts).

Usage: python tools/screenshot.py RECORDING.rrd OUT.png [--at HH:MM:SS] [--size 1600x900]
Needs a Vulkan software driver on headless Linux (Debian: mesa-vulkan-drivers).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("recording", type=Path)
    parser.add_argument("out", type=Path)
    parser.add_argument("--at", default=None, help="sim time HH:MM[:SS] (default: end of the recording)")
    parser.add_argument("--settle", type=float, default=4.0, help="seconds to let the viewer load")
    args = parser.parse_args(argv)
    import rerun_cli
    from rerun.experimental import ViewerClient

    from scenes.clock import parse_clock

    binary = str(Path(rerun_cli.__file__).parent / "rerun")
    os.environ.setdefault("WGPU_BACKEND", "vulkan")
    viewer = ViewerClient.spawn(headless=True, executable_path=binary, port=0 or 9877)
    try:
        viewer.open(str(args.recording.resolve()))
        time.sleep(args.settle)
        if args.at:
            viewer.set_time("sim_time", duration=parse_clock(args.at), play_state="paused")
            time.sleep(1.0)
        viewer.save_screenshot(str(args.out.resolve()))
    finally:
        viewer.quit()
    print(args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
