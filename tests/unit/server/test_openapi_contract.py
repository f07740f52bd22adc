"""The web UI's types are generated from `web/openapi.json`: it must be the server's schema."""

import json
from pathlib import Path

from groupwise.server.app import create_app
from groupwise.server.config import AppConfig
from groupwise.server.schemas.base import limits

WEB = Path(__file__).resolve().parents[3] / "web"
SAVED = WEB / "openapi.json"


def test_the_web_uis_saved_schema_is_the_servers(tmp_path):
    app = create_app(AppConfig(data_dir=tmp_path, start_worker=False))
    served = json.loads(json.dumps(app.openapi()))
    assert json.loads(SAVED.read_text()) == served, (
        "web/openapi.json is stale: cd web && npm run types:schema && npm run types"
    )


def test_the_web_uis_limits_are_the_servers():
    saved = json.loads((WEB / "src" / "limits.json").read_text())
    assert saved == limits(), "web/src/limits.json is stale: cd web && npm run types:schema"
