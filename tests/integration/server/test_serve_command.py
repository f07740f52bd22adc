"""`groupwise serve` refuses bad input in one line with exit code 2, before serving."""

import asyncio
import socket

import pytest

from groupwise.cli import main
from groupwise.commands.arguments import UsageError
from groupwise.commands.serve import _bind, _is_loopback, choose_session
from groupwise.storage import Database, sqlite_url
from groupwise.storage import sessions as repo


def _serve(tmp_path, capsys, *args: str) -> tuple[int, str]:
    try:
        code = main(["serve", "--data", str(tmp_path / "data"), *args])
    except SystemExit as exit_:  # argparse rejects malformed values itself
        code = exit_.code
    return code, capsys.readouterr().err.strip()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--env", "NoSuchEnv"], "NoSuchEnv"),
        (["--env", "GridWorld", "--pool-size", "5"], "--pool-size: Input should be greater"),
        (["--env", "GridWorld", "--rounds", "two"], "expected a whole number, got 'two'"),
        (["--env", "GridWorld", "--port", "70000"], "port number <= 65535"),
        (["--env", "GridWorld", "--settings", "{nope"], "--settings is not JSON"),
        (["--env", "GridWorld", "--settings", '{"frame_size": 33}'], "setting frame_size"),
        (["--env", "GridWorld", "--settings", '{"colour": 1}'], "setting colour"),
        (["--env", "GridWorld", "--fragment-length", "2000"], "--fragment-length"),
        (["--env", "Hopper", "--clip-seconds", "20"], "horizon of at least"),  # 2500 steps
        (["--session", "s-nope"], "no session 's-nope'"),
        ([], "--env is required"),
        (["--env", "GridWorld", "--token", " "], "--token must not be empty"),
    ],
)
def test_bad_input_is_one_line_and_exit_code_2(tmp_path, capsys, args, message):
    code, err = _serve(tmp_path, capsys, *args)
    assert code == 2
    # one line (argparse's own errors put the usage above it)
    assert message in err.splitlines()[-1], err
    assert "Traceback" not in err


def test_an_env_whose_episodes_end_before_a_behaviour_is_refused_and_nothing_created(
    tmp_path, capsys
):
    """InvertedPendulum-v5 ends when the pole tips (3-20 random steps): its session's round 0
    could never be prepared (issue 23), so serve refuses it as the New-session page does."""
    code, err = _serve(tmp_path, capsys, "--env", "InvertedPendulum-v5", "--port", "0")
    assert code == 2 and len(err.splitlines()) == 1
    assert "episodes of InvertedPendulum-v5 lasted" in err
    assert "none long enough for one window of 25 steps (clip_seconds = 1 s)" in err
    assert not (tmp_path / "data" / "groupwise.db").exists()


def test_a_port_in_use_is_a_usage_error(tmp_path, capsys):
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        code, err = _serve(tmp_path, capsys, "--env", "GridWorld", "--port", str(port))
    assert code == 2 and f"cannot listen on 127.0.0.1:{port}" in err


def test_resuming_with_other_settings_needs_new(tmp_path, capsys):
    with socket.socket() as taken:  # stop after the session is chosen, before serving
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = str(taken.getsockname()[1])
        code, _ = _serve(tmp_path, capsys, "--env", "GridWorld", "--port", port)
        assert code == 2  # the session was created before the port was found taken
        code, err = _serve(
            tmp_path, capsys, "--env", "GridWorld", "--pool-size", "50", "--port", port
        )
    assert code == 2 and "--new" in err


def test_a_session_stores_its_clip_duration_in_steps_and_resumes_with_it(tmp_path):
    url = sqlite_url(tmp_path / "groupwise.db")
    first = choose_session(url, "Hopper", "groupwise", {"clip_seconds": 2.0}, None, False)
    database = Database(url)
    with database.read() as s:
        stored = repo.get_session(s, first.session_id).settings
    database.dispose()
    assert (stored["fragment_length"], stored["clip_seconds"]) == (250, 2.0)
    for same in ({"clip_seconds": 2.0}, {}, {"fragment_length": 250}):
        again = choose_session(url, "Hopper", "groupwise", same, None, False)
        assert (again.session_id, again.verb) == (first.session_id, "resuming")
    with pytest.raises(UsageError, match="--new"):
        choose_session(url, "Hopper", "groupwise", {"clip_seconds": 1.0}, None, False)


@pytest.mark.parametrize(
    ("host", "loopback"),
    [("127.0.0.1", True), ("127.0.0.2", True), ("::1", True), ("localhost", True),
     ("0.0.0.0", False), ("192.168.1.20", False), ("example.org", False)],
)  # fmt: skip
def test_only_loopback_hosts_go_without_a_token(host, loopback):
    assert _is_loopback(host) is loopback


class _Accepted(asyncio.Protocol):
    """Reports the TCP_NODELAY option of the connection it is made for."""

    def __init__(self, nodelay: "asyncio.Future[int]") -> None:
        self.nodelay = nodelay

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        sock = transport.get_extra_info("socket")
        self.nodelay.set_result(sock.getsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY))
        transport.close()


async def _nodelay_of_an_accepted_connection(sock: socket.socket) -> int:
    """Serve `sock` as uvicorn does (`loop.create_server(sock=...)`) and connect once."""
    loop = asyncio.get_running_loop()
    nodelay: asyncio.Future[int] = loop.create_future()
    server = await loop.create_server(lambda: _Accepted(nodelay), sock=sock)
    _, writer = await asyncio.open_connection(*sock.getsockname()[:2])
    try:
        return await asyncio.wait_for(nodelay, 10)
    finally:
        writer.close()
        server.close()
        await server.wait_closed()


def test_accepted_connections_send_answers_without_delay():
    # asyncio sets TCP_NODELAY only on connections of an IPPROTO_TCP socket; without it
    # every answer waited ~40 ms for a delayed ACK (Nagle; the latency itself is measured by
    # benchmarks/submit_latency.py)
    with _bind("127.0.0.1", 0) as sock:
        assert sock.proto == socket.IPPROTO_TCP
        assert asyncio.run(_nodelay_of_an_accepted_connection(sock)) != 0
