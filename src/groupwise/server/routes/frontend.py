"""The built web UI at ``/`` (``src/groupwise/static``, package data), or a page saying how to
build it."""

from pathlib import Path

from fastapi import FastAPI
from fastapi.responses import HTMLResponse
from fastapi.staticfiles import StaticFiles

NOT_BUILT = """<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>groupwise</title></head>
<body style="font-family: sans-serif; max-width: 40em; margin: 3em auto">
<h1>groupwise</h1>
<p>The server is running, but the web UI has not been built: no <code>{index}</code>.</p>
<p>In a checkout, build it with <code>make setup</code> (or <code>cd web &amp;&amp; npm ci
&amp;&amp; npm run build</code>) and reload this page; an installed package needs to be
reinstalled after the build. The API is at <a href="/api/docs">/api/docs</a>.</p>
</body></html>
"""


def mount_frontend(app: FastAPI, static_dir: Path) -> None:
    """Serve `static_dir` at ``/`` when it holds ``index.html``; else a build hint at ``/``.

    Call after every API router is included: the mount catches all other paths.
    """
    index = static_dir / "index.html"
    if index.is_file():
        app.mount("/", StaticFiles(directory=static_dir, html=True), name="frontend")
        return

    @app.get("/", include_in_schema=False)
    def not_built() -> HTMLResponse:
        return HTMLResponse(NOT_BUILT.format(index=index))
