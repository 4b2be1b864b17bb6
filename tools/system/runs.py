"""Runs of `chronav launch`: where they live, which are live, whose they are, how to join one.

Why one module: the launcher writes a run, and `chronav agenda`, `chronav dsr dump` and
`chronav chaos` find and join it; if each had its own idea of the runs directory, of "live" or
of the connect file, a tool could attach to the wrong system.  Everything about that lives here:

- **The runs directory** is ``$CHRONAV_RUNS`` or ``./recordings`` of the current directory, never
  the installed source tree: a run belongs to whoever started it, where they started it.
- **A run's security** (``prepare_run_security``): every run gets its own Zenoh users with
  random passwords, one per agent, one tool identity (``agenda_tool``: may write only as an
  ``agenda_tool-*`` agent) and one reader (subscribe and query, never put).  The run's router
  loads the usrpwd dictionary and an ACL (``run_acl``) giving each user write rights on its own
  key space only (``chronav/<graph>/*/<agent>``: delta, state, members and any later key kind),
  so on loopback too nobody can publish as an agent without that agent's password.  Agents get
  their password through a 0600 file named in ``CHRONAV_ZENOH_PASSWORD_FILE`` (never on a
  command line, never in the environment itself).
- **The connect file** ``<run>/connect.json`` (mode 0600: owner only) holds the endpoint, the
  graph, the launcher's pid and start time and the tool and reader credentials: a tool that can
  read it may join the run, nobody else can.
- **Discovery**: ``--run latest`` takes the newest *live* run of the *current OS user* (its
  connect file is owned by this uid); ``--run DIR`` or a run id refuses another user's run.
- **Liveness**: a run is live while it has no ``result.json`` and its launcher process (same pid
  *and* same start time, so a recycled pid does not count) is running.
"""

from __future__ import annotations

import json
import os
import stat
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

RUNS_ENV = "CHRONAV_RUNS"
CONNECT_FILE = "connect.json"
CONNECT_FORMAT = "chronav-run/1"
RESULT_FILE = "result.json"
SECRETS_DIR = "secrets"
ACL_FILE = "acl.json5"
ROUTER_CREDENTIALS = "router_credentials.txt"
#: staff tools (`chronav agenda`, `chronav chaos`) write as agent "agenda_tool-<suffix>"
TOOL_AGENT_PREFIX = "agenda_tool"
TOOL_USER = "agenda_tool"
READER_USER = "reader"
Role = Literal["tool", "reader"]
HOW_TO_START = ("start one with `chronav launch SCENE` (in this directory, or with the same "
                f"${RUNS_ENV}), then use --run latest")


class RunError(Exception):
    """No usable run: missing, finished, someone else's, or its connect file is unusable."""


# ---------------------------------------------------------------------------------------------
# The runs directory.
# ---------------------------------------------------------------------------------------------

def runs_dir(environ: Mapping[str, str] | None = None) -> Path:
    """``$CHRONAV_RUNS``, else ``./recordings`` of the current directory (absolute)."""
    env = os.environ if environ is None else environ
    text = (env.get(RUNS_ENV) or "").strip()
    return (Path(text).expanduser() if text else Path.cwd() / "recordings").absolute()


# ---------------------------------------------------------------------------------------------
# Per-run users, passwords and access control.
# ---------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Identity:
    """A Zenoh usrpwd identity of one run."""

    user: str
    password: str = field(repr=False)


@dataclass(frozen=True)
class RunSecurity:
    """The files of a run's credentials: what the router loads and what each agent reads."""

    secrets_dir: Path
    credentials_file: Path          # the router's usrpwd dictionary
    acl_file: Path                  # the router's access-control list
    agents: dict[str, Identity]
    tool: Identity
    reader: Identity

    def password_file(self, agent: str) -> Path:
        return self.secrets_dir / f"{agent}.password"

    def agent_env(self, agent: str) -> dict[str, str]:
        """What an agent process needs to authenticate: its user, and a file with its password."""
        return {"CHRONAV_ZENOH_USER": self.agents[agent].user,
                "CHRONAV_ZENOH_PASSWORD_FILE": str(self.password_file(agent))}

    def router_args(self) -> list[str]:
        return ["--credentials", str(self.credentials_file), "--acl", str(self.acl_file)]


_READ_MESSAGES = ["put", "delete", "query", "reply", "declare_subscriber", "declare_queryable",
                  "liveliness_token", "liveliness_query", "declare_liveliness_subscriber"]
_JOIN_MESSAGES = ["declare_subscriber", "declare_liveliness_subscriber", "liveliness_query", "query"]
_WRITE_MESSAGES = ["put", "delete", "declare_queryable", "reply", "liveliness_token"]


def run_acl(graph: str, agents: Sequence[str]) -> dict[str, Any]:
    """The Zenoh ``access_control`` object of one run (default deny).

    Every user of the run may read the graph and take part in state transfer; each agent's
    user may write (publish, serve state, hold a member token) only on keys whose last chunk
    is its own agent name; the tool user only as ``agenda_tool-<suffix>``; the reader nothing.
    Same structure as deploy/acl.json5, which does this per host for multi-machine setups."""
    space = f"chronav/{graph}"
    users = [*agents, TOOL_USER, READER_USER]
    rules: list[dict[str, Any]] = [
        {"id": "read_graph", "permission": "allow", "flows": ["egress"], "messages": _READ_MESSAGES,
         "key_exprs": [f"{space}/**"]},
        {"id": "join_graph", "permission": "allow", "flows": ["ingress"], "messages": _JOIN_MESSAGES,
         "key_exprs": [f"{space}/**"]},
    ]
    subjects: list[dict[str, Any]] = [{"id": "run_users", "usernames": users}]
    policies: list[dict[str, Any]] = [{"id": "run_users_read", "rules": ["read_graph", "join_graph"],
                                       "subjects": ["run_users"]}]
    writers = [(agent, agent, [f"{space}/*/{agent}"]) for agent in agents]
    writers.append((TOOL_USER, TOOL_USER, [f"{space}/*/{TOOL_AGENT_PREFIX}-$*"]))
    for ident, user, keys in writers:
        rules.append({"id": f"write_as_{ident}", "permission": "allow", "flows": ["ingress"],
                      "messages": _WRITE_MESSAGES, "key_exprs": keys})
        subjects.append({"id": f"user_{ident}", "usernames": [user]})
        policies.append({"id": f"{ident}_writes", "rules": [f"write_as_{ident}"],
                         "subjects": [f"user_{ident}"]})
    return {"enabled": True, "default_permission": "deny", "rules": rules, "subjects": subjects,
            "policies": policies}


def _write_private(path: Path, text: str) -> None:
    """Create ``path`` readable and writable by the owner only (0600), atomically.

    The temporary file is created with mode 0600 from the start (never world-readable, not
    even for an instant) and then renamed over the target."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as handle:
            handle.write(text)
        os.chmod(tmp, 0o600)       # in case the file existed with another mode
        tmp.replace(path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def _new_password() -> str:
    import secrets  # here, not at import: every `chronav` command loads this module (8 ms)

    return secrets.token_urlsafe(24)   # [A-Za-z0-9_-]: never a ':' (the dictionary separator)


def prepare_run_security(run_dir: Path, graph: str, agents: Sequence[str]) -> RunSecurity:
    """Generate the run's users and passwords; write the router's dictionary and ACL and one
    password file per agent under ``<run>/secrets`` (0700, files 0600)."""
    secrets_dir = run_dir / SECRETS_DIR
    secrets_dir.mkdir(mode=0o700, parents=True, exist_ok=True)
    os.chmod(secrets_dir, 0o700)
    identities = {agent: Identity(agent, _new_password()) for agent in agents}
    tool, reader = Identity(TOOL_USER, _new_password()), Identity(READER_USER, _new_password())
    dictionary = "".join(f"{i.user}:{i.password}\n" for i in (*identities.values(), tool, reader))
    security = RunSecurity(secrets_dir, secrets_dir / ROUTER_CREDENTIALS, run_dir / ACL_FILE,
                           identities, tool, reader)
    _write_private(security.credentials_file, dictionary)
    for agent, identity in identities.items():
        _write_private(security.password_file(agent), identity.password + "\n")
    _write_private(security.acl_file, json.dumps({"access_control": run_acl(graph, agents)}, indent=2))
    return security


# ---------------------------------------------------------------------------------------------
# The connect file.
# ---------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class ConnectInfo:
    """What ``connect.json`` says about a run."""

    run_dir: Path
    run_id: str
    endpoint: str
    graph: str
    launcher_pid: int
    launcher_started: float
    identities: dict[str, Identity]

    def identity(self, role: Role) -> Identity:
        return self.identities[role]


def process_start_time(pid: int) -> float | None:
    """When process ``pid`` started (seconds since the epoch), None if there is no such process."""
    import psutil

    try:
        return float(psutil.Process(pid).create_time())
    except (psutil.NoSuchProcess, psutil.AccessDenied, psutil.ZombieProcess, ValueError):
        return None


def write_connect_file(run_dir: Path, *, run_id: str, endpoint: str, graph: str,
                       security: RunSecurity) -> Path:
    """``connect.json``, mode 0600: how the run's owner's tools join it while it is live."""
    pid = os.getpid()
    document = {
        "format": CONNECT_FORMAT, "run_id": run_id, "endpoint": endpoint, "graph": graph,
        "launcher_pid": pid, "launcher_started": process_start_time(pid), "uid": os.getuid(),
        "users": {"tool": {"user": security.tool.user, "password": security.tool.password},
                  "reader": {"user": security.reader.user, "password": security.reader.password}},
    }
    path = run_dir / CONNECT_FILE
    _write_private(path, json.dumps(document, indent=2))
    return path


def _owner_name(uid: int) -> str:
    import pwd

    try:
        return pwd.getpwuid(uid).pw_name
    except KeyError:
        return f"uid {uid}"


def read_connect_file(run_dir: Path) -> ConnectInfo:
    """The run's connect file, refused (RunError) unless it is this user's, private and whole."""
    path = run_dir / CONNECT_FILE
    try:
        info = path.stat()
    except FileNotFoundError:
        if (run_dir / RESULT_FILE).exists():
            raise RunError(f"run {run_dir} has finished (it has {RESULT_FILE}); nothing is running there"
                           ) from None
        raise RunError(f"{path} is missing; is {run_dir} a run directory of `chronav launch`?") from None
    if info.st_uid != os.getuid():
        raise RunError(f"run {run_dir} belongs to {_owner_name(info.st_uid)}, not to you; tools join only "
                       "their own user's runs")
    if stat.S_IMODE(info.st_mode) & 0o077:
        raise RunError(f"{path} is readable by other users (mode {stat.S_IMODE(info.st_mode):o}); the "
                       f"run's credentials may have leaked. Restart the run (or `chmod 600 {path}`)")
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise RunError(f"{path}: cannot read it as JSON ({exc})") from None
    return _connect_info(run_dir, path, data)


def _connect_info(run_dir: Path, path: Path, data: object) -> ConnectInfo:
    if not isinstance(data, dict) or data.get("format") != CONNECT_FORMAT:
        raise RunError(f"{path}: not a connect file of this chronav (expected \"format\": "
                       f"\"{CONNECT_FORMAT}\"); start a new run with `chronav launch`")
    try:
        users = data["users"]
        identities = {role: Identity(str(users[role]["user"]), str(users[role]["password"]))
                      for role in ("tool", "reader")}
        return ConnectInfo(run_dir=run_dir, run_id=str(data["run_id"]), endpoint=str(data["endpoint"]),
                           graph=str(data["graph"]), launcher_pid=int(data["launcher_pid"]),
                           launcher_started=float(data["launcher_started"] or 0.0), identities=identities)
    except (KeyError, TypeError, ValueError) as exc:
        raise RunError(f"{path}: incomplete connect file ({type(exc).__name__}: {exc})") from None


# ---------------------------------------------------------------------------------------------
# Liveness and discovery.
# ---------------------------------------------------------------------------------------------

def launcher_alive(info: ConnectInfo) -> bool:
    """The launcher that wrote the file still runs: same pid and the same start time."""
    started = process_start_time(info.launcher_pid)
    return started is not None and abs(started - info.launcher_started) < 1.0


def run_is_alive(run_dir: Path) -> bool:
    """Live: no result.json yet, and the launcher that wrote its connect file still runs."""
    if (run_dir / RESULT_FILE).exists():
        return False
    try:
        return launcher_alive(read_connect_file(run_dir))
    except RunError:
        return False


@dataclass(frozen=True)
class RunListing:
    """The runs under a runs directory, sorted newest first."""

    mine_live: list[Path]
    mine_ended: list[Path]
    others: list[Path]


def list_runs(directory: Path) -> RunListing:
    live, ended, others = [], [], []
    candidates = []
    # a long run's days are runs inside its folder (tools/week.py): `--run latest` finds today's
    for path in [*directory.glob(f"*/{CONNECT_FILE}"), *directory.glob(f"*/*/{CONNECT_FILE}")]:
        try:
            info = path.stat()
        except OSError:
            continue
        candidates.append((info.st_mtime, path.parent, info.st_uid))
    for _mtime, run_dir, uid in sorted(candidates, key=lambda c: c[0], reverse=True):
        if uid != os.getuid():
            others.append(run_dir)
        elif run_is_alive(run_dir):
            live.append(run_dir)
        else:
            ended.append(run_dir)
    return RunListing(live, ended, others)


def latest_live_run(directory: Path) -> Path:
    """The newest live run of this OS user under ``directory``."""
    listing = list_runs(directory)
    if listing.mine_live:
        return listing.mine_live[0]
    seen = []
    if listing.mine_ended:
        seen.append(f"{len(listing.mine_ended)} of yours ended")
    if listing.others:
        seen.append(f"{len(listing.others)} of other users skipped")
    where = f"{directory}" + (f" ({', '.join(seen)})" if seen else "")
    raise RunError(f"no live run of yours under {where}; {HOW_TO_START}")


def latest_finished_run(directory: Path) -> Path:
    """The newest run of this OS user under ``directory`` that has finished (wrote its
    ``result.json``, launched or in-process): what ``latest`` means for commands that read a run
    after the fact (`chronav export latest`), where a live run has nothing to read yet."""
    finished = []
    for path in directory.glob(f"*/{RESULT_FILE}"):
        try:
            info = path.stat()
        except OSError:
            continue
        if info.st_uid == os.getuid():
            finished.append((info.st_mtime, path.parent))
    if not finished:
        raise RunError(f"no finished run of yours under {directory}; run one with `chronav launch SCENE` (in this "
                       f"directory, or with the same ${RUNS_ENV}) and wait for it to end")
    return max(finished, key=lambda item: item[0])[1].absolute()


def find_run_dir(run: str, directory: Path) -> Path:
    """``latest``, a run directory, or a run id under ``directory``."""
    if run == "latest":
        return latest_live_run(directory)
    for candidate in (Path(run), directory / run):
        if candidate.is_dir():
            return candidate.absolute()
    raise RunError(f"--run {run!r}: no such run directory (looked at {Path(run)} and {directory / run}); "
                   "use --run latest or the run directory `chronav launch` printed")


def open_run(run: str, directory: Path | None = None) -> ConnectInfo:
    """The connect file of a run that is live (RunError saying what is wrong otherwise)."""
    run_dir = find_run_dir(run, directory or runs_dir())
    info = read_connect_file(run_dir)
    if (run_dir / RESULT_FILE).exists() or not launcher_alive(info):
        raise RunError(f"run {run_dir.name} is no longer running (its launcher, pid "
                       f"{info.launcher_pid}, has ended); {HOW_TO_START}")
    return info

