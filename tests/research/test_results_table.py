"""research/results_table.py on real files: run folders as `groupwise case-study` writes them
→ `collect` → runs.csv → `render` into a README → `check`; and `check` failing on an
edited table."""

import csv
import json
from pathlib import Path
from types import ModuleType

import pytest
from tests.research.conftest import research_script


@pytest.fixture(scope="module")
def rt() -> ModuleType:
    return research_script("results_table")


CASE_STUDY = (
    "round,comparisons_total,pairs_total,tied_share_total,label_error_untied_total,"
    "pool_score_sd,pool_score_max,target_score_mean,wall_s"
)
ROUNDS = "round,comparisons,pairs,reward_loss"


def make_run(
    folder: Path, name: str, seed: int, scores: list[float], success: float, pool_size: int | None
) -> Path:
    """A run folder with every file `groupwise case-study --out` writes."""
    run = folder / name
    run.mkdir(parents=True)
    config = {
        "loop": {"env": "Hopper-backflip", "decision_maker": "groupwise", "seed": seed,
                 "pool_size": pool_size, "comparisons": 380},
        "reward": {"hidden_sizes": [64, 64], "lr": 0.001},
        "training": {"pretrain_steps": 0},
    }  # fmt: skip
    (run / "config.json").write_text(json.dumps(config))
    study = [CASE_STUDY]
    loop = [ROUNDS]
    for r, score in enumerate(scores):
        pairs = 100 * (r + 1) + seed
        study.append(
            f"{r},{40 * (r + 1)},{pairs},0.125,0.0312500001,0.4{r},1.{r},{score!r},{60.5 * (r + 1)}"
        )
        loop.append(f"{r},40,{pairs},0.30000000000000004")
    (run / "case-study.csv").write_text("\n".join(study) + "\n")
    (run / "rounds.csv").write_text("\n".join(loop) + "\n")
    rounds = list(range(len(scores)))
    summary = {
        "target": {"name": "hopper-backflip", "env": "Hopper-backflip", "threshold": 1.0,
                   "description": "turns"},
        "decision_maker": "groupwise",
        "comparisons": 40 * len(scores),
        "preference_pairs": 100 * len(scores) + seed,
        "final": {"scores": [2.0, 0.5, 1.5, 1.2, 0.1], "success_rate": success,
                  "stretch_rate": 0.2},
        "takeaway": {"round": rounds[-1], "by": "teacher", "rounds": rounds, "scores": scores,
                     "returns": [10.0 * s for s in scores], "verdicts": [], "success_rate": 0.4},
    }  # fmt: skip
    (run / "summary.json").write_text(json.dumps(summary))
    (run / "takeaway.json").write_text(json.dumps({"config": {"episodes": 3}, "round": 2}))
    return run


README = """# Runs

<!-- table:summary pool=no -->
<!-- /table -->

Text between the tables stays.

<!-- table:runs seed="1|0" title="DM, pools" -->
<!-- /table -->
"""


@pytest.fixture
def folder(tmp_path: Path) -> Path:
    folder = tmp_path / "pools"
    make_run(folder, "hopper-backflip-groupwise-s0", 0, [0.1, 0.25, 1.75], 0.6, None)
    make_run(folder, "big/hopper-backflip-groupwise-s1", 1, [0.0, 0.5, 0.25], 0.2, 500)
    (folder / "README.md").write_text(README)
    return folder


def test_collect_keeps_every_value_as_written(rt: ModuleType, folder: Path) -> None:
    assert rt.main(["collect", str(folder)]) == 0
    with (folder / "runs.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert [(r["setup"], r["seed"], r["round"]) for r in rows] == [
        ("big", "1", "0"), ("big", "1", "1"), ("big", "1", "2"),
        ("", "0", "0"), ("", "0", "1"), ("", "0", "2"),
    ]  # fmt: skip
    first = rows[3]
    assert first["label"] == "groupwise" and rows[0]["label"] == "groupwise · pools of 500"
    assert first["label_error_untied_total"] == "0.0312500001"  # never re-formatted
    assert first["loop.reward_loss"] == "0.30000000000000004"
    assert first["summary.final.scores"] == "2.0;0.5;1.5;1.2;0.1"
    assert first["takeaway.config.episodes"] == "3"
    assert [r["takeaway.return"] for r in rows[3:]] == ["1.0", "2.5", "17.5"]
    assert "summary.target.description" not in first  # prose, the same on every row
    # only what differs between the runs is a column; the rest is runs-config.json
    assert first["config.loop.pool_size"] == "" and rows[0]["config.loop.pool_size"] == "500"
    assert "config.reward.lr" not in first
    shared = json.loads((folder / "runs-config.json").read_text())
    assert shared["reward"] == {"hidden_sizes": [64, 64], "lr": 0.001}
    assert "seed" not in shared["loop"] and "pool_size" not in shared["loop"]


def test_render_then_check_round_trip(
    rt: ModuleType, folder: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rt.main(["collect", str(folder)])
    assert rt.main(["check", str(folder)]) == 1  # the tables are still empty
    assert rt.main(["render", str(folder)]) == 0
    text = (folder / "README.md").read_text()
    assert "Text between the tables stays." in text
    assert (
        "| hopper-backflip | groupwise · pools of 500 | 1 | **0/1** | 0/1 | 0/1 | 120 | 301 |"
        in text
    )
    assert "| hopper-backflip | groupwise | 1 | **1/1** | 0/1 | 0/1 | 120 | 300 |" in text
    runs = text.split('title="DM, pools" -->\n')[1].splitlines()
    assert runs[0].startswith("| target | DM, pools | seed |")
    # seed="1|0" orders the rows: seed 1 first
    assert runs[2] == (
        "| hopper-backflip | groupwise · pools of 500 | 1 | 120 | 301 | 0.12 | 0.03 "
        "| 0.00, 0.50, 0.25 | 1/5 | 1/5 | 182 s |"
    )
    assert runs[3].endswith("| 0.10, 0.25, 1.75 | 3/5 | 1/5 | 182 s |")
    capsys.readouterr()
    assert rt.main(["check", str(folder)]) == 0
    assert capsys.readouterr().out == ""


def test_check_fails_on_an_edited_table(
    rt: ModuleType, folder: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rt.main(["collect", str(folder)])
    rt.main(["render", str(folder)])
    readme = folder / "README.md"
    edited = readme.read_text().replace("0.10, 0.25, 1.75 | 3/5", "0.10, 0.25, 1.80 | 3/5")
    readme.write_text(edited)
    capsys.readouterr()
    assert rt.main(["check", str(folder)]) == 1
    out = capsys.readouterr().out
    assert "-| hopper-backflip | groupwise | 0 |" in out and "1.80" in out
    assert "+| hopper-backflip | groupwise | 0 |" in out and "1.75" in out


def test_a_bad_marker_is_one_line_error(
    rt: ModuleType, folder: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rt.main(["collect", str(folder)])
    (folder / "README.md").write_text("<!-- table:runs seed=7 -->\n<!-- /table -->\n")
    assert rt.main(["check", str(folder)]) == 2
    assert capsys.readouterr().err == "results_table: table:runs seed=7: no run matches\n"
    (folder / "README.md").write_text("<!-- table:plot -->\n<!-- /table -->\n")
    assert rt.main(["render", str(folder)]) == 2
    assert "unknown table kind 'plot'" in capsys.readouterr().err


def test_collect_without_runs_is_an_error(
    rt: ModuleType, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert rt.main(["collect", str(tmp_path)]) == 2
    assert "no run folder" in capsys.readouterr().err


SETUPS = """<!-- table:setups head="setup|seeds|last round|per seed" cells="seeds|last|scores"
all pools :: bold=last
pools of 500 :: setup=big
-->
<!-- /table -->

<!-- table:matrix rows=hopper-backflip cell="{last} ({takeaway}; stretch {stretch})"
every run :: bold=hopper-backflip:last
the default pools :: setup="" cell={last}
-->
<!-- /table -->
"""


def test_setups_and_matrix_tables(rt: ModuleType, folder: Path) -> None:
    rt.main(["collect", str(folder)])
    (folder / "README.md").write_text(SETUPS)
    assert rt.main(["render", str(folder)]) == 0
    text = (folder / "README.md").read_text()
    assert (
        "| setup | seeds | last round | per seed |\n"
        "|---|---|---:|---|\n"
        "| all pools | 0–1 | **1/2** | 1.75, 0.25 |\n"  # seed order, whatever the CSV's
        "| pools of 500 | 1 | 0/1 | 0.25 |\n"
    ) in text
    assert (
        "| target | every run | the default pools |\n"
        "|---|---:|---:|\n"
        "| hopper-backflip | **1/2** (0/2; stretch 0/2) | 1/1 |\n"
    ) in text
    assert rt.main(["check", str(folder)]) == 0
