"""The app in-process (no uvicorn, no worker process) on a real database and data dir.

`client` and `prepared` run every test that uses them on SQLite and on PostgreSQL
(`db_backend`, tests/conftest.py); the worker tests, which import them, stay on SQLite.

`prepared` runs the real worker job in this process to open round 0 of a tiny GridWorld
session, so the round's endpoints have a real pool, tree, clips and suggestions to serve.
"""

import uuid
import warnings
from pathlib import Path

import pytest

with warnings.catch_warnings():  # Starlette 1.x announces a move from httpx to httpx2
    warnings.simplefilter("ignore", UserWarning)
    from fastapi.testclient import TestClient

from tests.conftest import new_database_url
from tests.postgres import BACKENDS

from groupwise.server import AppConfig, create_app
from groupwise.server.context import AppContext
from groupwise.worker.process import Worker

TINY = {
    "recipe": "paper",  # no pre-training on a MuJoCo env: tests stay fast
    "pool_size": 16,
    "fragment_length": 10,
    "ppo_steps_per_round": 64,
    "comparisons_per_round": 0,
    "rounds": 2,
    "frame_size": 32,
    "render_workers": 0,
    "eval_episodes": 1,
    "research": {"ppo": {"n_envs": 1, "n_steps": 32, "batch_size": 16, "n_epochs": 1}},
}
"""Settings that make a GridWorld round take about a second."""


def make_client(data_dir: Path, **config: object) -> TestClient:
    options = {"start_worker": False, "allowed_hosts": None, "static_dir": data_dir / "no-web"}
    app = create_app(AppConfig(data_dir=data_dir, **{**options, **config}))
    return TestClient(app)


def context_of(client: TestClient) -> AppContext:
    return client.app.state.context  # type: ignore[attr-defined]  # app.state is untyped


def run_worker_once(client: TestClient) -> None:
    """Run the next waiting job in this process, as the worker process would."""
    context = context_of(client)
    assert Worker(context.db, context.data_dir, poll_s=0.1).run_next()


def new_session(client: TestClient, mode: str = "groupwise", **settings: object) -> dict:
    response = client.post(
        "/api/sessions", json={"env": "GridWorld", "mode": mode, "settings": {**TINY, **settings}}
    )
    assert response.status_code == 201, response.text
    return response.json()


def post_judgement(
    client: TestClient, sid: str, left: list[str], right: list[str], round_index: int = 0
) -> dict:
    """A person's answer "left is better" to a comparison they built in the chart."""
    body = {
        "client_id": str(uuid.uuid4()),
        "round": round_index,
        "left": left,
        "right": right,
        "label": "left",
        "source": "explored",
    }
    response = client.post(f"/api/sessions/{sid}/judgements", json=body)
    assert response.status_code == 201, response.text
    return response.json()


@pytest.fixture(scope="session", params=BACKENDS)
def db_backend(request: pytest.FixtureRequest) -> str:
    """The app's tests run on SQLite and on PostgreSQL."""
    return str(request.param)


@pytest.fixture
def client(tmp_path, database_url) -> TestClient:
    with make_client(tmp_path, database_url=database_url) as test_client:
        yield test_client


@pytest.fixture(scope="module")
def prepared(request, tmp_path_factory, db_backend) -> tuple[TestClient, str, str]:
    """A client and two sessions (groupwise, pairwise) whose round 0 is open."""
    data = tmp_path_factory.mktemp("data")
    url = new_database_url(request, db_backend, data)
    with make_client(data, database_url=url) as test_client:
        groupwise = new_session(test_client)["id"]
        pairwise = new_session(test_client, "pairwise")["id"]
        run_worker_once(test_client)
        run_worker_once(test_client)
        yield test_client, groupwise, pairwise
