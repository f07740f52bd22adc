"""Property-based fuzzing of the whole API from its own OpenAPI schema (schemathesis).

Every operation gets generated requests, valid ("positive") and invalid ("negative"),
twice: with whatever session id the generator makes up, and aimed at a real session whose
round is open, so the handlers behind the 404 are reached too. Every answer must be below
500 and match the schema (status code and body). The event stream is left out: it never
ends by design (it is tested live in tests/integration/server/).

(schemathesis' own pytest plugin does not run under pytest 9, so the hypothesis tests are
built here from each operation's strategy.)
"""

import json

import pytest
import schemathesis
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from schemathesis import GenerationMode
from schemathesis.checks import not_a_server_error
from schemathesis.specs.openapi.checks import response_schema_conformance


@schemathesis.serializer("application/x-ndjson", "application/vnd.apache.parquet")
def _raw_body(ctx, value) -> bytes:
    """The import endpoint's bodies: send generated strings or bytes as they are."""
    if isinstance(value, bytes):
        return value
    return value.encode() if isinstance(value, str) else json.dumps(value).encode()


EXAMPLES = 10
"""Examples per operation, mode and session-id variant (about 800 requests in all)."""
CHECKS = [not_a_server_error, response_schema_conformance]


@pytest.fixture(scope="module")
def operations(prepared):
    client, _, _ = prepared
    schema = schemathesis.openapi.from_asgi("/api/openapi.json", client.app)
    found = [result.ok() for result in schema.exclude(path_regex=r"/events$").get_all_operations()]
    assert len(found) >= 15
    # ending the round last keeps the open round's handlers reachable for the others
    return sorted(found, key=lambda operation: operation.path.endswith("/end-round"))


def _fuzz(operation, session_id: str | None) -> None:
    strategy = st.one_of(
        operation.as_strategy(GenerationMode.POSITIVE),
        operation.as_strategy(GenerationMode.NEGATIVE),
    )

    @given(case=strategy)
    @settings(
        max_examples=EXAMPLES,
        deadline=None,
        database=None,
        suppress_health_check=list(HealthCheck),
    )
    def run(case) -> None:
        parameters = case.path_parameters
        if session_id is not None and parameters and "session_id" in parameters:
            parameters["session_id"] = session_id
            if "round_index" in parameters:
                parameters["round_index"] = 0
        case.validate_response(case.call(), checks=CHECKS)

    run()


def test_made_up_ids_never_fail(operations):
    for operation in operations:
        _fuzz(operation, None)


def test_a_real_session_never_fails(operations, prepared):
    for operation in operations:
        _fuzz(operation, prepared[1])
