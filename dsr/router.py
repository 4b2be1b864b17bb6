"""A Zenoh router as a Python process: `python -m dsr.router --listen tcp/127.0.0.1:PORT`.

Why Python: no `zenohd` binary is packaged on the registries we use; the eclipse-zenoh wheel can
run in router mode.  Agents connect to it in client mode.  Prints one "ready" line on stdout.

ACL denials (dsr/acl_denials.py): Zenoh drops a message its access-control list denies without
a word to the sender; the router counts each one (by user, message kind and key), logs the
first ones and then a summary every 10 s, and answers `chronav/<graph>/router?stats` with the
counts (`chronav dsr stats` shows them).

Security (docs/deployment.md): `--credentials` turns on user/password authentication (every
client must present a listed user), `--acl` loads an access-control list on the key space,
`--tls-*` serve tls/ endpoints.  The same settings can come from CHRONAV_ZENOH_* variables or a
json5 Zenoh config file (`--config` / CHRONAV_ZENOH_CONFIG); flags override both.  The router
ignores CHRONAV_ZENOH_MODE and CHRONAV_ZENOH_CONNECT (those tell agents how to reach it).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections.abc import Mapping
from pathlib import Path

from pydantic import ValidationError

from dsr.acl_denials import AclDenials, capture_zenoh_log, stats_key
from dsr.config import (DEFAULT_ROUTER, ENV_CONNECT, ENV_LISTEN, ENV_MODE, ZenohSettings,
                        check_endpoint, clean_zenoh_error)
from dsr.errors import ConfigError
from dsr.log_rotation import LogRotation
from dsr.process import exit_on_sigterm


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="python -m dsr.router", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--listen", action="append", default=None,
                        help=f"endpoint to listen on (repeatable; default {DEFAULT_ROUTER} or "
                             f"{ENV_LISTEN} or the config file)")
    parser.add_argument("--connect", action="append", default=None,
                        help="another router to connect to (repeatable)")
    parser.add_argument("--lease-ms", type=int, default=None,
                        help="link lease (default 2000, or CHRONAV_ZENOH_LEASE_MS)")
    parser.add_argument("--config", type=Path, default=None, help="json5 Zenoh config file")
    parser.add_argument("--credentials", type=Path, default=None,
                        help="usrpwd dictionary, one user:password per line (enables auth)")
    parser.add_argument("--acl", type=Path, default=None,
                        help="json5 file with {access_control: {...}}")
    parser.add_argument("--tls-cert", type=Path, default=None, help="server certificate (PEM)")
    parser.add_argument("--tls-key", type=Path, default=None, help="server private key (PEM)")
    parser.add_argument("--tls-root-ca", type=Path, default=None,
                        help="CA that signed client certificates (mutual TLS)")
    parser.add_argument("--mtls", action="store_true", help="require client certificates")
    return parser.parse_args(argv)


def router_settings(args: argparse.Namespace, environ: Mapping[str, str] | None = None
                    ) -> ZenohSettings:
    """Environment (minus the agents' mode/connect) < config file < command-line flags."""
    env = dict(os.environ if environ is None else environ)
    env.pop(ENV_MODE, None)
    env.pop(ENV_CONNECT, None)
    base = ZenohSettings.from_env(env)
    fields = base.model_dump(exclude_unset=True)
    if base.password is not None:
        fields["password"] = base.password
    fields["mode"] = "router"
    overrides = {"listen": args.listen, "connect": args.connect, "lease_ms": args.lease_ms,
                 "config_file": args.config, "credentials_file": args.credentials,
                 "acl_file": args.acl, "tls_certificate": args.tls_cert,
                 "tls_private_key": args.tls_key, "tls_root_ca": args.tls_root_ca,
                 "mtls": args.mtls or None}
    for flag, endpoints in (("--listen", args.listen), ("--connect", args.connect)):
        for endpoint in endpoints or ():
            try:
                check_endpoint(endpoint)
            except ConfigError as exc:
                raise ConfigError(f"{flag} {exc}") from None
    fields.update({k: v for k, v in overrides.items() if v is not None})
    if "listen" not in fields and fields.get("config_file") is None:
        fields["listen"] = [DEFAULT_ROUTER]
    try:
        return ZenohSettings(**fields)
    except ValidationError as exc:     # one line naming the setting, not pydantic's report
        first = exc.errors()[0]
        where = f"--{str(first['loc'][0]).replace('_', '-')}: " if first["loc"] else ""
        raise ConfigError(where + str(first["msg"]).removeprefix("Value error, ")) from None


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    import zenoh
    try:
        settings = router_settings(args)
        conf = settings.to_zenoh_config()
        log_rotation = LogRotation.from_env()
    except (ConfigError, ValueError) as exc:
        print(f"dsr.router: {exc}", file=sys.stderr)
        return 2
    exit_on_sigterm()
    denials = AclDenials(counting=settings.acl_file is not None or settings.config_file is not None)
    if denials.counting:
        capture_zenoh_log(denials.on_log_line)   # the ACL's refusals, counted and logged
    try:
        session = zenoh.open(conf)
    except zenoh.ZError as exc:
        print(f"dsr.router: cannot open router ({settings.describe()}): {clean_zenoh_error(exc)}",
              file=sys.stderr)
        return 1
    try:
        session.declare_queryable(stats_key("*"), denials.on_query, complete=True)
        print(f"dsr.router ready on {','.join(settings.listen) or '(config file endpoints)'}"
              f" ({settings.describe()})", flush=True)
        # Woken every second to cut its log on the hour in a real-time run (dsr/log_rotation.py).
        while True:
            time.sleep(1.0)
            if log_rotation is not None:
                log_rotation.maybe_rotate()
    except (KeyboardInterrupt, SystemExit):
        pass
    finally:
        session.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
