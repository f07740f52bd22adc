"""`groupwise serve` refuses bad input in one line with exit code 2, before serving."""

import socket

import pytest

from groupwise.cli import main
from groupwise.commands.serve import _bind, _is_loopback


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


@pytest.mark.parametrize(
    ("host", "loopback"),
    [("127.0.0.1", True), ("127.0.0.2", True), ("::1", True), ("localhost", True),
     ("0.0.0.0", False), ("192.168.1.20", False), ("example.org", False)],
)  # fmt: skip
def test_only_loopback_hosts_go_without_a_token(host, loopback):
    assert _is_loopback(host) is loopback


def test_the_listening_socket_is_tcp_so_answers_are_not_delayed():
    # asyncio sets TCP_NODELAY only on connections of an IPPROTO_TCP socket; without it
    # every answer waited ~40 ms for a delayed ACK (see test_session_flow's latency test)
    with _bind("127.0.0.1", 0) as sock:
        assert sock.proto == socket.IPPROTO_TCP
