"""The interactive app's back end (docs/app.md): FastAPI app, schemas, training worker.

    app = create_app(AppConfig(data_dir=Path("groupwise-data")))   # then run with uvicorn

Modules: `app` (create_app), `config`, `schemas` (the contract), `routes/` (one router per
resource), `state` / `pool_views` / `events` / `transfer` (what the handlers call),
`security` (host, token, body limit), `supervisor` and `worker` (the training process),
`jobs` (preparing a round, training after one), `suggestions` (what a round offers from
the ensemble), `progress`.
"""

from groupwise.server.app import create_app
from groupwise.server.config import AppConfig

__all__ = ["AppConfig", "create_app"]
