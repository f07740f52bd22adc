"""Shared fixtures for the env tests."""

from pathlib import Path

import pytest


@pytest.fixture(autouse=True)
def _in_temporary_directory(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Run each test in its own directory: MuJoCo writes MUJOCO_LOG.TXT into the working
    directory when it warns (Walker2d's and HalfCheetah's XML use a deprecated attribute)."""
    monkeypatch.chdir(tmp_path)
