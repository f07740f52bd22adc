"""Writing and reading ``agent.zip`` (the package's docstring lists what it holds)."""

import json
import os
import zipfile
from dataclasses import dataclass
from pathlib import Path

from groupwise.agent_file.readme import readme
from groupwise.agent_file.summary import (
    SETTINGS_FILE,
    SUMMARY_FILE,
    ZIP_CONFIG,
    ZIP_NORMALISER,
    ZIP_POLICY,
    ZIP_REWARD,
    ZIP_ROUNDS,
    AgentSummary,
)


def write_agent_zip(
    path: Path,
    checkpoint: Path,
    summary: AgentSummary,
    run_dir: Path,
) -> None:
    """Pack `checkpoint`'s policy, normaliser and reward ensemble with `summary`, a README,
    and `run_dir`'s ``config.json``, ``rounds.csv`` and ``settings.json`` (when present)
    into `path`, replaced atomically."""
    partial = path.with_name(f".{path.name}.partial")
    with zipfile.ZipFile(partial, "w", compression=zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("README.md", readme(summary))
        archive.writestr(SUMMARY_FILE, summary.to_json() + "\n")
        for name in (ZIP_POLICY, ZIP_NORMALISER, ZIP_REWARD):
            archive.write(checkpoint / name, name)
        for name in (ZIP_CONFIG, ZIP_ROUNDS, SETTINGS_FILE):
            if (run_dir / name).is_file():
                archive.write(run_dir / name, name)
    os.replace(partial, path)


@dataclass(frozen=True)
class AgentArchive:
    """An ``agent.zip`` read into memory: its summary and every file's bytes by name."""

    summary: AgentSummary
    files: dict[str, bytes]


def read_agent_zip(path: str | os.PathLike[str]) -> AgentArchive:
    """Read an ``agent.zip`` (from the app's "Download agent", or a run's directory).

    Raises:
        FileNotFoundError: no such file.
        ValueError: not a groupwise agent file.
    """
    try:
        with zipfile.ZipFile(path) as archive:
            files = {name: archive.read(name) for name in archive.namelist()}
    except zipfile.BadZipFile as error:
        raise ValueError(f"{path} is not a zip file: {error}") from None
    missing = [n for n in (SUMMARY_FILE, ZIP_POLICY, ZIP_NORMALISER) if n not in files]
    if missing:
        raise ValueError(f"{path} is not a groupwise agent: it lacks {', '.join(missing)}")
    return AgentArchive(AgentSummary.from_dict(json.loads(files[SUMMARY_FILE])), files)
