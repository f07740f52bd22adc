"""`groupwise serve`: run the interactive web app (docs/app.md) for one env.

Creates a session for ``--env`` (or resumes the newest unfinished one of that env and mode,
or the one named by ``--session``), starts the HTTP server and its training worker, and
prints the page's URL. Binds 127.0.0.1 by default; any other host needs a token, which is
generated and printed when ``--token`` is not given.
"""

import argparse
import ipaddress
import json
import math
import secrets
import socket
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from groupwise.commands.arguments import UsageError, int_at_least, writable_dir

if TYPE_CHECKING:
    from groupwise.storage import Database


def _number(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


SETTING_FLAGS: dict[str, Callable[[str], Any]] = {
    "pool_size": int_at_least(0),
    "fragment_length": int_at_least(0),
    "clip_seconds": _number,
    "round_seconds": _number,
    "comparisons_per_round": int_at_least(0),
    "ppo_steps_per_round": int_at_least(0),
    "final_steps": int_at_least(0),
    "rounds": int_at_least(0),
    "suggestions": int_at_least(0),
    "seed": int_at_least(0),
}
"""Session settings with a flag of their own (``--pool-size`` …); the rest via --settings."""


def _port(text: str) -> int:
    value = int_at_least(0)(text)
    if value > 65535:
        raise argparse.ArgumentTypeError(f"expected a port number <= 65535, got {value}")
    return value


def register(subparsers: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    serve = subparsers.add_parser(
        "serve",
        help="run the interactive web app: compare behaviours in the browser while it trains",
    )
    serve.add_argument("--env", help="GridWorld, Hopper, ... or a Gymnasium id")
    serve.add_argument(
        "--dataset",
        metavar="minari:ID|PATH",
        help="label a recorded dataset instead of an agent's behaviours, with no agent: "
        "minari:<id> (the local Minari store; never downloaded), a Minari dataset directory "
        "or a D4RL-style .hdf5 file; its env is the dataset's unless --env names one "
        "(docs/bring-your-own.md)",
    )
    serve.add_argument("--mode", choices=["groupwise", "pairwise"], default="groupwise")
    serve.add_argument("--data", type=Path, default=Path("groupwise-data"), help="data directory")
    serve.add_argument("--db", help="SQLAlchemy database URL (default: DATA/groupwise.db)")
    serve.add_argument("--host", default="127.0.0.1", help="address to bind (default loopback)")
    serve.add_argument("--port", type=_port, default=8000, help="port (0: any free port)")
    serve.add_argument("--token", help="access token (generated for a non-loopback host)")
    serve.add_argument("--session", help="serve this session instead of the newest unfinished")
    serve.add_argument("--new", action="store_true", help="always start a new session")
    serve.add_argument(
        "--ray",
        metavar="ADDRESS",
        help="render clips on demand as tasks on this Ray cluster ('auto', 'ray://HOST:10001', "
        "'local': a Ray of this machine) instead of processes of the server; every node needs "
        "groupwise installed",
    )
    serve.add_argument(
        "--training-workers",
        type=int_at_least(1),
        default=1,
        metavar="N",
        help="training worker processes; each trains a share of the sessions, so open "
        "sessions train on N cores (default 1: on 2 cores PPO has one, the server the other)",
    )
    for name, kind in SETTING_FLAGS.items():
        serve.add_argument(
            f"--{name.replace('_', '-')}",
            type=kind,
            default=None,
            help=f"session setting {name} (docs/app.md)",
        )
    serve.add_argument(
        "--settings",
        help="more session settings as a JSON object, e.g. '{\"frame_size\": 120}'",
    )
    serve.set_defaults(handler=run)


def _settings_overrides(args: argparse.Namespace) -> dict[str, Any]:
    overrides: dict[str, Any] = {}
    if args.settings:
        try:
            extra = json.loads(args.settings)
        except json.JSONDecodeError as error:
            raise UsageError(f"--settings is not JSON: {error.msg}") from None
        if not isinstance(extra, dict):
            raise UsageError("--settings must be a JSON object")
        overrides.update(extra)
    for name in SETTING_FLAGS:
        value = getattr(args, name)
        if value is not None:
            overrides[name] = value
    if args.dataset is not None:
        overrides["dataset"] = args.dataset
    return overrides


def _is_loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def _bind(host: str, port: int) -> socket.socket:
    """The listening socket, bound here so a taken port is a one-line usage error and
    ``--port 0`` can print the port it got."""
    try:
        family, kind, proto, _, address = socket.getaddrinfo(
            host, port, type=socket.SOCK_STREAM, proto=socket.IPPROTO_TCP
        )[0]
        # proto must be IPPROTO_TCP: only then does asyncio set TCP_NODELAY on accepted
        # connections; with proto 0 every answer waited ~40 ms for a delayed ACK (Nagle).
        sock = socket.socket(family, kind, proto)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind(address)
    except OSError as error:
        raise UsageError(f"cannot listen on {host}:{port}: {error.strerror or error}") from None
    return sock


@dataclass(frozen=True)
class Chosen:
    session_id: str
    env: str
    mode: str
    verb: str  # "new" or "resuming"


def choose_session(
    database_url: str,
    env: str | None,
    mode: str,
    overrides: dict[str, Any],
    session_id: str | None,
    new: bool,
) -> Chosen:
    """The session to serve: `session_id`, else the newest unfinished one of `env` and
    `mode` (unless `new`), else a new one with the settings `overrides`.

    Raises UsageError (a clash of options), StorageError (unknown env or session, or an
    env whose episodes cannot hold a behaviour: `server.state.check_env`, before the
    database is opened; a dataset that cannot be labelled: `check_dataset`),
    pydantic.ValidationError (bad settings). With a dataset in `overrides` (``--dataset``)
    the env defaults to the dataset's and only a session of that dataset is resumed.
    """
    from groupwise.server.state import check_new_session
    from groupwise.storage import SessionSettings
    from groupwise.storage import sessions as repo

    settings = SessionSettings.model_validate(overrides)
    if session_id is not None:
        with _database(database_url) as db, db.write() as s:
            found = repo.get_session(s, session_id)
            if env is not None and env != found.env:
                raise UsageError(f"session {session_id} is a {found.env} session, not {env}")
            _check_same_settings(found.id, found.settings, overrides)
            return Chosen(found.id, found.env, found.mode, "resuming")
    if env is None and settings.dataset is None:
        raise UsageError("--env is required unless --session or --dataset names one")
    # before the database: a refused env or dataset creates nothing
    env, settings = check_new_session(env, settings)
    overrides = {**overrides, "dataset": settings.dataset} if settings.dataset else overrides
    with _database(database_url) as db, db.write() as s:
        resumable = None if new else repo.find_resumable(s, env, mode, settings.dataset)
        if resumable is not None:
            _check_same_settings(resumable.id, resumable.settings, overrides)
            return Chosen(resumable.id, env, mode, "resuming")
        created = repo.create_session(s, env, mode, settings)
        return Chosen(created.id, env, mode, "new")


@contextmanager
def _database(url: str) -> "Iterator[Database]":
    """The database at `url` with its schema, disposed of on exit."""
    from groupwise.storage import Database

    db = Database(url, pool_size=1)
    try:
        db.create_schema()
        yield db
    finally:
        db.dispose()


def _check_same_settings(
    session_id: str, stored: dict[str, Any], overrides: dict[str, Any]
) -> None:
    from groupwise.storage import SessionSettings

    wanted = SessionSettings.stored({**stored, **overrides})
    if wanted != SessionSettings.stored(stored):
        raise UsageError(
            f"session {session_id} was started with other settings; pass --new to start a "
            "new session with these, or leave the setting flags out to resume it"
        )


RAY_CONNECT_S = 5.0
"""Seconds `--ray HOST:PORT` waits for the Ray head to accept a connection."""


def _join_ray(address: str) -> None:
    """Connect to the Ray cluster that renders clips now, so a wrong address is a usage
    error before the server starts (`clips.on_demand.RayBackend` then uses the connection)."""
    import logging

    try:
        import ray
    except ImportError:
        raise UsageError("--ray: Ray is not installed (pip install groupwise[ray])") from None
    host, _, port = address.rpartition(":")
    if host and port.isdigit() and "://" not in address:
        # Ray retries an unreachable head for minutes before it gives up
        try:
            socket.create_connection((host, int(port)), timeout=RAY_CONNECT_S).close()
        except OSError as error:
            reason = error.strerror or error
            raise UsageError(f"--ray {address}: no Ray head answers there ({reason})") from None
    try:
        ray.init(address=address, logging_level=logging.WARNING, log_to_driver=False)
    except Exception as error:  # ConnectionError, ValueError, RuntimeError: Ray says which
        raise UsageError(f"--ray {address}: cannot join the Ray cluster: {error}") from None


def run(args: argparse.Namespace) -> int:
    import uvicorn
    from pydantic import ValidationError

    from groupwise.server import AppConfig, create_app
    from groupwise.server.config import LOOPBACK_HOSTS
    from groupwise.storage import StorageError

    loopback = _is_loopback(args.host)
    token = args.token
    if token is not None and not token.strip():
        raise UsageError("--token must not be empty")
    if not loopback and token is None:
        token = secrets.token_urlsafe(24)
    data = writable_dir(args.data).resolve()
    config = AppConfig(
        data_dir=data,
        database_url=args.db,
        token=token,
        allowed_hosts=LOOPBACK_HOSTS if loopback else None,
        ray_address=args.ray,
        training_workers=args.training_workers,
    )
    try:
        chosen = choose_session(
            config.db_url,
            env=args.env,
            mode=args.mode,
            overrides=_settings_overrides(args),
            session_id=args.session,
            new=args.new,
        )
    except ValidationError as error:
        first = error.errors()[0]
        field = ".".join(str(p) for p in first["loc"])
        flag = f"--{field.replace('_', '-')}" if field in SETTING_FLAGS else f"setting {field}"
        raise UsageError(f"{flag}: {first['msg']}") from None
    except StorageError as error:  # unknown env or session
        raise UsageError(str(error)) from None
    if args.ray is not None:
        _join_ray(args.ray)
    sock = _bind(args.host, args.port)
    port = sock.getsockname()[1]
    shown = f"[{args.host}]" if ":" in args.host else args.host
    query = f"?session={chosen.session_id}" + (f"&token={token}" if token else "")
    print(
        f"groupwise: {chosen.verb} {chosen.mode} {chosen.env} session {chosen.session_id}\n"
        f"open http://{shown}:{port}/{query}",
        flush=True,
    )
    if token is not None and args.token is None:
        print(f"token: {token}", flush=True)
    server = uvicorn.Server(
        uvicorn.Config(
            create_app(config),
            log_level="warning",
            access_log=False,
            timeout_graceful_shutdown=3,
        )
    )
    server.run(sockets=[sock])
    print("groupwise: server stopped", file=sys.stderr)
    return 0
