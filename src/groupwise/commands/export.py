"""`groupwise export` and `groupwise import`: a session's judgements and pairs to a file
(JSONL or Parquet, docs/export.md) and a file to a new session of another data directory;
``--format ipl-npz | pt-indices`` writes the pairs for offline preference learners instead
(`groupwise.storage.export_offline`).

``groupwise export SESSION --data DIR --states -o feedback.parquet`` writes the judgements
with the compared behaviours' observations, actions and true rewards (read from the
round's pools in DIR); ``groupwise import feedback.parquet --data OTHER`` makes a new,
finished session in OTHER whose pairs train a reward model there without those pools
(`groupwise.storage.states.preference_dataset`).
"""

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from groupwise.commands.arguments import UsageError, writable_dir

if TYPE_CHECKING:
    from groupwise.storage.export_format import SessionExport

FORMATS = ("jsonl", "parquet", "ipl-npz", "pt-indices")
OFFLINE_FORMATS = ("ipl-npz", "pt-indices")
"""Formats for offline preference learners (`groupwise.storage.export_offline`): always with
the compared behaviours' states."""


def register(subparsers: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    export = subparsers.add_parser(
        "export", help="write a session's judgements and pairs to a JSONL or Parquet file"
    )
    export.add_argument("session", nargs="?", help="session id (default: the newest session)")
    _add_database(export)
    export.add_argument(
        "-o",
        "--output",
        type=Path,
        help="file to write (default: SESSION.FORMAT here; pt-indices: a directory, SESSION-pt)",
    )
    export.add_argument(
        "--format",
        choices=FORMATS,
        help="jsonl or parquet (default: from the output's suffix, .npz: ipl-npz, else "
        "jsonl); ipl-npz: the pairs as IPL's and CPL's comparison .npz; pt-indices: as "
        "Preference Transformer's and Uni-RLHF's index pickles over a dataset.npz "
        "(docs/export.md)",
    )
    export.add_argument(
        "--states",
        action="store_true",
        help="also each compared behaviour's observations, actions and true rewards",
    )
    export.add_argument(
        "--no-true-rewards",
        dest="true_rewards",
        action="store_false",
        help="with --states: leave the env's true rewards out",
    )
    export.set_defaults(handler=run_export)

    imported = subparsers.add_parser(
        "import", help="import an exported session (JSONL or Parquet) as a new, finished one"
    )
    imported.add_argument("file", type=Path, help="an export of `groupwise export` or the app")
    _add_database(imported)
    imported.set_defaults(handler=run_import)


def _add_database(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--data", type=Path, default=Path("groupwise-data"), help="data directory")
    parser.add_argument("--db", help="SQLAlchemy database URL (default: DATA/groupwise.db)")


def _format_of(args: argparse.Namespace) -> str:
    if args.format:
        return str(args.format)
    suffix = args.output.suffix.lstrip(".").lower() if args.output else ""
    if suffix == "npz":
        return "ipl-npz"
    return suffix if suffix in ("jsonl", "parquet") else "jsonl"


def _judgements_text(total: int, undone: int) -> str:
    """ "40 judgements (6 undone)": every judgement a file or database holds, undone ones
    included (issue 40: the import printed only the live ones)."""
    return f"{total} judgements" + (f" ({undone} undone)" if undone else "")


def run_export(args: argparse.Namespace) -> int:
    from groupwise.storage import Database, StorageError, default_url
    from groupwise.storage.export import StatesExport, export_session
    from groupwise.storage.export_jsonl import to_jsonl
    from groupwise.storage.export_parquet import to_parquet
    from groupwise.storage.sessions import list_sessions

    fmt = _format_of(args)
    data = args.data.resolve()
    if args.db is None and not (data / "groupwise.db").is_file():
        raise UsageError(f"{data} holds no groupwise database; pass --data DIR or --db URL")
    db = Database(args.db or default_url(data), pool_size=1)
    try:
        with db.read() as s:
            session_id = args.session
            if session_id is None:
                newest = list_sessions(s)
                if not newest:
                    raise UsageError("the database holds no session")
                session_id = newest[0].id
            with_states = args.states or fmt in OFFLINE_FORMATS
            states = StatesExport(data, args.true_rewards) if with_states else None
            export = export_session(s, session_id, states)
    except StorageError as error:
        raise UsageError(str(error)) from None
    finally:
        db.dispose()
    if fmt in OFFLINE_FORMATS:
        return _write_offline(export, fmt, args.output, session_id)
    body = to_parquet(export) if fmt == "parquet" else to_jsonl(export)
    output = args.output or Path(f"{session_id}.{fmt}")
    writable_dir(output.resolve().parent)
    output.write_bytes(body)
    what = _judgements_text(len(export.judgements), sum(j.undone for j in export.judgements))
    if args.states:
        what += f", {sum(len(b.names) for b in export.behaviours)} behaviours' states"
    print(f"groupwise: wrote {output} ({what})", file=sys.stderr)
    return 0


def _write_offline(export: "SessionExport", fmt: str, output: Path | None, session_id: str) -> int:
    """Write an export's pairs as `fmt` (`OFFLINE_FORMATS`) for offline learners."""
    from groupwise.storage import StorageError
    from groupwise.storage.export_offline import offline_pairs, to_ipl_npz, write_pt_indices

    try:
        pairs = offline_pairs(export)
        if fmt == "ipl-npz":
            target = output or Path(f"{session_id}.npz")
            writable_dir(target.resolve().parent)
            target.write_bytes(to_ipl_npz(pairs))
        else:
            target = output or Path(f"{session_id}-pt")
            writable_dir(target.resolve().parent)
            write_pt_indices(pairs, target)
    except StorageError as error:
        raise UsageError(str(error)) from None
    except OSError as error:
        raise UsageError(f"cannot write {target}: {error.strerror or error}") from None
    rewards = "" if pairs.reward_1 is not None else ", without true rewards"
    print(
        f"groupwise: wrote {target} ({len(pairs)} pairs of {pairs.length}-step behaviours"
        f"{rewards})",
        file=sys.stderr,
    )
    return 0


def run_import(args: argparse.Namespace) -> int:
    from groupwise.storage import Database, StorageError, default_url
    from groupwise.storage.counts import counts
    from groupwise.storage.export import import_session
    from groupwise.storage.export_jsonl import from_jsonl
    from groupwise.storage.export_parquet import from_parquet
    from groupwise.storage.judgements import list_judgements

    try:
        body = args.file.read_bytes()
    except OSError as error:
        raise UsageError(f"cannot read {args.file}: {error.strerror or error}") from None
    parse = from_parquet if body.startswith(b"PAR1") else from_jsonl
    data = writable_dir(args.data).resolve()
    db = Database(args.db or default_url(data), pool_size=1)
    try:
        export = parse(body)
        db.create_schema()
        with db.write() as s:
            session = import_session(s, export, data_dir=data)
            counted = counts(s, session)
            stored = list_judgements(s, session.id, include_undone=True)
            session_id = session.id
    except StorageError as error:
        raise UsageError(f"{args.file}: {error}") from None
    finally:
        db.dispose()
    print(
        f"groupwise: imported {args.file} as session {session_id} "
        f"({_judgements_text(len(stored), sum(j.undone for j in stored))}, "
        f"{counted.pairs_total} pairs" + (", with states" if export.behaviours else "") + ")",
    )
    return 0
