"""The New-session form's route refuses an env whose observations cannot be taught with the
one line the command line prints, and accepts one that observes a dict (issue 42)."""

import pytest
from tests.observation_envs import env_name


@pytest.mark.parametrize(
    ("gym_id", "reason"),
    [
        ("ImageObs-v0", "its observation is an image, Box(32, 32, 3) of uint8"),
        ("PixelsAndStateObs-v0", "its observation at ['pixels'] is an image"),
        ("DiscreteObs-v0", "its observation is Discrete"),
    ],
)
def test_an_observation_that_cannot_be_taught_is_422_with_one_line(client, gym_id, reason):
    for route in ("/api/settings/resolve", "/api/sessions"):  # the form checks, then creates
        response = client.post(route, json={"env": env_name(gym_id)})
        assert response.status_code == 422, route
        detail = response.json()["detail"]
        assert detail.startswith(f"env {env_name(gym_id)} cannot be taught here: {reason}")
        assert "\n" not in detail
    assert client.get("/api/sessions").json() == []


def test_a_dict_observation_env_is_accepted(client):
    response = client.post(
        "/api/sessions", json={"env": env_name("DictObs-v0"), "settings": {"clip_seconds": 1}}
    )
    assert response.status_code == 201, response.text
    assert response.json()["env"] == env_name("DictObs-v0")
