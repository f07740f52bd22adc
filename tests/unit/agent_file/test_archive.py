"""agent.zip written and read back by the format layer alone (no torch, SB3 or run)."""

import zipfile

import pytest

from groupwise.agent_file.archive import read_agent_zip, write_agent_zip
from groupwise.agent_file.summary import FORMAT, AgentSummary, RoundSummary

SUMMARY = AgentSummary(
    format=FORMAT,
    env="GridWorld",
    round=1,
    env_steps=128,
    measure="true return",
    true_return_mean=41.5,
    true_return_std=3.2,
    normalize_obs=True,
    clip_obs=5.0,
    epsilon=1e-6,
    rounds=tuple(
        RoundSummary(r, r == 0, 4 * (r == 0), 4 * (r == 0), 64 * (r + 1), 40.0 + r, 3.0)
        for r in range(2)
    ),
)


def _run_dir(tmp_path):
    checkpoint = tmp_path / "checkpoints" / "round-0001"
    checkpoint.mkdir(parents=True)
    for name in ("policy.zip", "vecnormalize.npz", "reward.pt"):
        (checkpoint / name).write_bytes(name.encode())
    (tmp_path / "config.json").write_text("{}")
    return checkpoint


def test_an_agent_zip_holds_its_files_and_reads_back_as_written(tmp_path):
    checkpoint = _run_dir(tmp_path)
    write_agent_zip(tmp_path / "agent.zip", checkpoint, SUMMARY, tmp_path)
    archive = read_agent_zip(tmp_path / "agent.zip")
    assert archive.summary == SUMMARY
    assert archive.files["policy.zip"] == b"policy.zip"
    assert archive.files["config.json"] == b"{}"
    assert "rounds.csv" not in archive.files and "settings.json" not in archive.files
    readme = archive.files["README.md"].decode()
    assert "round 1" in readme and "-5.0, 5.0)" in readme  # the recorded normalisation
    assert not list(tmp_path.glob(".*.partial"))


def test_a_zip_without_a_policy_is_not_an_agent(tmp_path):
    with zipfile.ZipFile(tmp_path / "other.zip", "w") as archive:
        archive.writestr("agent.json", SUMMARY.to_json())
    with pytest.raises(ValueError, match=r"lacks policy\.zip, vecnormalize\.npz"):
        read_agent_zip(tmp_path / "other.zip")
    (tmp_path / "text.zip").write_text("not a zip")
    with pytest.raises(ValueError, match="is not a zip file"):
        read_agent_zip(tmp_path / "text.zip")
