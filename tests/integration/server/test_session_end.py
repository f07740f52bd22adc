"""The end of an app session on a real server and worker process, then continued headless
with `groupwise train --from-session` (docs/app.md, "Session end")."""

import csv
import json

from tests.integration.server.conftest import TINY_FLAGS, TINY_SETTINGS, judgement

import groupwise
from groupwise.cli import main
from groupwise.clips.video import probe


def _rounds(directory):
    with (directory / "rounds.csv").open() as handle:
        return list(csv.DictReader(handle))


def _train(capsys, *args):
    """`groupwise train …` in this process: (exit code, stdout, stderr)."""
    code = main(["train", *args])
    out, err = capsys.readouterr()
    return code, out, err


def test_final_phase_then_from_session_continues_headless(serve, capsys):
    flags = list(TINY_FLAGS)
    flags[flags.index("--rounds") + 1] = "1"
    server = serve("--env", "GridWorld", *flags, settings={**TINY_SETTINGS, "final_steps": 128})
    sid = server.session
    server.wait_for("ready", 0)
    with server.client() as http:
        stored = http.post(f"/api/sessions/{sid}/judgements", json=judgement(0, ["b1"], ["b2"]))
        assert stored.status_code == 201
        assert http.post(f"/api/sessions/{sid}/end-round").json()["phase"] == "training"
        server.wait_for("finished", 1)
        agent = http.get(f"/api/sessions/{sid}/agent").json()
        assert [r["feedback"] for r in agent["rounds"]] == [True, False]

    directory = server.data / "sessions" / sid
    rows = _rounds(directory)
    assert [(r["round"], r["comparisons"], r["pairs"]) for r in rows][1] == ("1", "0", "0")
    assert json.loads((directory / "config.json").read_text())["loop"]["decision_maker"] == "human"
    assert any((directory / "tb").rglob("events.out.tfevents.*"))
    assert probe(directory / "agent.mp4").frames >= 1
    server.stop()  # the headless continuation works on the directory alone

    code, _, err = _train(capsys, "--from-session", str(directory), "--rounds", "1")
    assert code == 2 and "--dm" in err
    code, _, err = _train(capsys, "--from-session", str(directory), "--steps", "9", "--env", "X")
    assert code == 2 and "leave out --env" in err

    code, out, err = _train(capsys, "--from-session", str(directory), "--steps", "64", "-q")
    assert code == 0, err
    assert "agent.zip" in out
    rows = _rounds(directory)
    assert [r["round"] for r in rows] == ["0", "1", "2"]
    assert int(rows[2]["env_steps"]) >= int(rows[1]["env_steps"]) + 64

    code, _, err = _train(
        capsys, "--from-session", str(directory), "--rounds", "1", "--dm", "groupwise", "-q"
    )
    assert code == 0, err
    rows = _rounds(directory)
    # round 3 answered by the simulated DM, round 4 the final phase again
    assert [r["round"] for r in rows] == ["0", "1", "2", "3", "4"]
    assert int(rows[3]["judgements"]) > 0 and rows[4]["comparisons"] == "0"
    agent = groupwise.load_agent(directory / "agent.zip")
    assert agent.summary.round == 4
    assert [r.feedback for r in agent.summary.rounds] == [True, False, False, True, False]
    assert agent.evaluate(episodes=1).returns.shape == (1,)
