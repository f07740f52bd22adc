"""Print the server's OpenAPI schema (what `GET /api/openapi.json` serves) without running it,
and write the server's limits the page needs as numbers (`src/limits.json`).

../.venv/bin/python scripts/openapi.py > openapi.json     (npm run types:schema)
"""

import json
import sys
import tempfile
from pathlib import Path

from groupwise.server.app import create_app
from groupwise.server.config import AppConfig
from groupwise.server.schemas.base import limits

with tempfile.TemporaryDirectory() as tmp:
    app = create_app(AppConfig(data_dir=Path(tmp), start_worker=False))
    json.dump(app.openapi(), sys.stdout, indent=1, sort_keys=True)
    sys.stdout.write("\n")
(Path(__file__).resolve().parents[1] / "src" / "limits.json").write_text(
    json.dumps(limits(), indent=1, sort_keys=True) + "\n"
)
