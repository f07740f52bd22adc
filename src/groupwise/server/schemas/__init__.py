"""Request and response schemas: the contract with the web UI (docs/app.md).

FastAPI publishes them as the OpenAPI schema at ``/api/openapi.json``, from which the web
UI's types are generated. Requests reject unknown fields; every string and list is bounded.

One module per resource, as `server.routes` has one router per resource: `meta` (envs,
health), `sessions`, `annotators`, `rounds` (tree, edges, suggestions), `judgements`,
`pairwise`, `agent` (the finished session's agent, more training), `training` (the learning
curve); `base` holds the base models, the shared field types, `ErrorOut` and `limits`.
"""
