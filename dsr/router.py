"""A Zenoh router as a Python process: `python -m dsr.router --listen tcp/127.0.0.1:PORT`.

Why Python: no `zenohd` binary is packaged on the registries we use; the eclipse-zenoh wheel can
run in router mode.  Agents connect to it in client mode.  Prints one "ready" line on stdout.
"""

from __future__ import annotations

import argparse
import sys
import threading

from dsr.config import DEFAULT_ROUTER, ZenohSettings
from dsr.errors import ConfigError
from dsr.process import exit_on_sigterm


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m dsr.router", description=__doc__)
    parser.add_argument("--listen", action="append", default=None,
                        help=f"endpoint to listen on (repeatable; default {DEFAULT_ROUTER})")
    parser.add_argument("--connect", action="append", default=[],
                        help="another router to connect to (repeatable)")
    parser.add_argument("--lease-ms", type=int, default=2000)
    args = parser.parse_args(argv)
    import zenoh
    try:
        settings = ZenohSettings(mode="router", listen=args.listen or [DEFAULT_ROUTER],
                                 connect=args.connect, lease_ms=args.lease_ms)
        conf = settings.to_zenoh_config()
    except (ConfigError, ValueError) as exc:
        print(f"dsr.router: {exc}", file=sys.stderr)
        return 2
    exit_on_sigterm()
    try:
        session = zenoh.open(conf)
    except zenoh.ZError as exc:
        print(f"dsr.router: cannot open router on {settings.listen}: {exc}", file=sys.stderr)
        return 1
    try:
        print(f"dsr.router ready on {','.join(settings.listen)}", flush=True)
        threading.Event().wait()
    except (KeyboardInterrupt, SystemExit):
        pass
    finally:
        session.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
