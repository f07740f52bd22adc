"""The app's guards (docs/app.md, "Security").

For every HTTP request, in this order:

1. **Host**: Starlette's `TrustedHostMiddleware`, configured by `trusted_hosts`: with
   `allowed_hosts`, a Host header naming anything else → 400 (plain text "Invalid host
   header"). A loopback server thereby refuses pages that reach it through DNS rebinding (a
   foreign name resolving to 127.0.0.1): without CORS a foreign page cannot read the
   answers, but could still send requests.
2. **Same origin** (`GuardMiddleware`): a state change (POST, PUT, PATCH, DELETE) that a
   browser marks as coming from another site → 403: ``Sec-Fetch-Site`` other than
   ``same-origin`` or ``none``, or an ``Origin`` other than the server's own (scheme and
   Host header). Clients that send neither header (scripts, the CLI, `WebTeacher`) are not
   browsers acting for a foreign page; the token guards them.
3. **Token** (`GuardMiddleware`): with a token, every ``/api`` and ``/clips`` request needs
   ``Authorization: Bearer <token>`` or ``?token=<token>`` (for ``<video src>``) → else 401.
   Compared in constant time. The built web UI's files stay public (they hold no data).
   **Who** (docs/teams.md): the server's token, or no token on a server without one, is the
   owner; an annotator's token (`identify`, looked up by its SHA-256) is that annotator,
   whether or not the server has a token; any other token → 401 (a removed annotator's
   too). An annotator reaches only their own session's routes (403 for another session's,
   for creating or importing one); the caller is ``scope["state"]["caller"]``
   (`storage.annotators.Caller`) for the routes, which refuse an annotator what only the
   owner may do.
4. **Body size** (`GuardMiddleware`): a body over `max_body_bytes` → 413, whether announced
   by Content-Length or streamed in chunks (counted as it arrives).
5. **JSON only** (`GuardMiddleware`): a state change under ``/api`` with a body that is not
   ``application/json`` → 415, whether the Content-Type names another type or is missing
   while a body is sent. The routes in `own_body_types` (the import, which takes JSONL and
   Parquet) check their types themselves. A plain HTML form or a "simple" cross-site fetch
   can only send form or text bodies, so this alone keeps them from changing anything.

No CORS headers are ever added, so a foreign page cannot send ``application/json`` at all
(it needs a preflight, which is never granted).
"""

import json
import secrets
from collections.abc import Callable
from urllib.parse import parse_qs

import anyio
from starlette.datastructures import Headers
from starlette.exceptions import HTTPException
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from groupwise.storage.annotators import OWNER_CALLER, Caller

PROTECTED_PREFIXES = ("/api", "/clips")
STATE_CHANGING = frozenset({"POST", "PUT", "PATCH", "DELETE"})
SAME_ORIGIN_SITES = frozenset({"same-origin", "none"})
"""``Sec-Fetch-Site`` values of requests from the app's own page (``none``: the user's own
navigation, e.g. a bookmark)."""
JSON_TYPE = "application/json"
SESSIONS = "/api/sessions"
NO_TOKEN = "a token is required: send Authorization: Bearer <token> or ?token="
BAD_TOKEN = (
    "this token is not valid here: a mistyped token, or an annotator's removed from their "
    "session; ask the session's owner for a new link"
)


class _Refused(HTTPException):
    """Raised from `receive` (body too large, or a body without a type): FastAPI passes
    HTTP exceptions on (others become 400s)."""


async def _send_error(send: Send, status: int, detail: str, extra: dict[str, str]) -> None:
    body = json.dumps({"detail": detail}).encode()
    headers = [
        (b"content-type", b"application/json"),
        (b"content-length", str(len(body)).encode()),
        *((k.encode(), v.encode()) for k, v in extra.items()),
    ]
    await send({"type": "http.response.start", "status": status, "headers": headers})
    await send({"type": "http.response.body", "body": body})


def trusted_hosts(allowed_hosts: tuple[str, ...] | None) -> list[str]:
    """`TrustedHostMiddleware`'s patterns for `AppConfig.allowed_hosts` (None: any host).

    Starlette compares an IPv6 literal with its brackets (``Host: [::1]:8000`` is ``[::1]``),
    so ``::1`` becomes ``[::1]``.
    """
    if allowed_hosts is None:
        return ["*"]
    return [f"[{h}]" if ":" in h and not h.startswith("[") else h for h in allowed_hosts]


def cross_site(scope: Scope, headers: Headers) -> str | None:
    """Why a browser request comes from another site (step 2 of the module docstring), or
    None when it comes from the app's own page or from no browser at all.

    The server's own origin is its scheme and the Host header, as the browser that loaded
    the page spelled it (behind a proxy that rewrites Host, the proxy must keep it).
    """
    site = headers.get("sec-fetch-site")
    if site is not None and site.strip().lower() not in SAME_ORIGIN_SITES:
        return f"a {site} request may not change anything here; use the app's own page"
    origin = headers.get("origin")
    own = f"{scope.get('scheme', 'http')}://{headers.get('host', '')}"
    if origin is not None and origin.strip().lower() != own.lower():
        return f"a request from {origin} may not change anything here; use the app's own page"
    return None


def not_json(headers: Headers) -> str | None:
    """Why a state change's body is not JSON (step 5 of the module docstring), or None.

    A request without Content-Type passes only when it announces no body; a streamed one is
    checked as its body arrives (`GuardMiddleware`).
    """
    content_type = headers.get("content-type")
    if content_type is None:
        length = headers.get("content-length")
        if length is not None and length.isdigit() and int(length) > 0:
            return f"send the body as {JSON_TYPE}; the request names no Content-Type"
        return None
    kind = content_type.split(";", 1)[0].strip().lower()
    if kind != JSON_TYPE:
        return f"send the body as {JSON_TYPE}, not {kind or 'an empty Content-Type'}"
    return None


def presented_tokens(scope: Scope, headers: Headers) -> list[str]:
    """The tokens a request carries: its Bearer header's, then its ``?token=`` values."""
    found = []
    header = headers.get("authorization", "")
    if header[:7].lower() == "bearer ":
        found.append(header[7:].strip())
    query = parse_qs(scope.get("query_string", b"").decode("latin-1"))
    return found + [v for v in query.get("token", []) if v]


def beyond_session(caller: Caller, method: str, path: str) -> str | None:
    """Why an annotator may not send this request (it leaves their own session), or None.

    Routes outside ``/api/sessions`` (envs, health, settings, clips) are everyone's; the
    session list answers an annotator their own session only (the route filters it).
    """
    if not path.startswith(SESSIONS) or caller.is_owner:
        return None
    rest = path[len(SESSIONS) :]
    if rest in ("", "/"):
        if method == "GET":
            return None
        return f"{caller.name} is an annotator of one session; only the owner creates sessions"
    if not rest.startswith("/"):
        return None  # another route, e.g. /api/sessionsX: not found anyway
    target = rest[1:].split("/", 1)[0]
    if target == "import":
        return f"{caller.name} is an annotator of one session; only the owner imports sessions"
    if target != caller.session_id:
        return (
            f"{caller.name}'s token is for session {caller.session_id}; it does not reach "
            f"session {target}"
        )
    return None


class GuardMiddleware:
    """Same-origin check, token check, body limit and JSON-only bodies (module docstring);
    the Host check is Starlette's.

    `own_body_types`: paths of routes that take other bodies than JSON and check the type
    themselves (the import). `identify`: the annotator whose token a string is, or None
    (a blocking database read: it runs on a worker thread).
    """

    def __init__(
        self,
        app: ASGIApp,
        *,
        token: str | None,
        max_body_bytes: int,
        own_body_types: frozenset[str] = frozenset(),
        identify: Callable[[str], Caller | None] | None = None,
    ) -> None:
        self.app = app
        self.token = token
        self.max_body_bytes = max_body_bytes
        self.own_body_types = own_body_types
        self.identify = identify

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        headers = Headers(scope=scope)
        changes = scope["method"] in STATE_CHANGING
        if changes and (reason := cross_site(scope, headers)) is not None:
            await _send_error(send, 403, reason, {})
            return
        if scope["path"].startswith(PROTECTED_PREFIXES):
            caller, refusal = await self._caller(scope, headers)
            if caller is None:
                await _send_error(send, 401, refusal, {"www-authenticate": "Bearer"})
                return
            if (reason := beyond_session(caller, scope["method"], scope["path"])) is not None:
                await _send_error(send, 403, reason, {})
                return
            scope.setdefault("state", {})["caller"] = caller
        length = headers.get("content-length")
        if length is not None and (not length.isdigit() or int(length) > self.max_body_bytes):
            await _send_error(send, 413, self._too_large(), {})
            return
        path = scope["path"]
        json_only = changes and path.startswith("/api") and path not in self.own_body_types
        if json_only and (reason := not_json(headers)) is not None:
            await _send_error(send, 415, reason, {})
            return
        untyped = json_only and "content-type" not in headers
        await self._limited(scope, receive, send, untyped)

    def _too_large(self) -> str:
        return f"the request body is larger than {self.max_body_bytes // 1024} KiB"

    async def _caller(self, scope: Scope, headers: Headers) -> tuple[Caller | None, str]:
        """Who sends the request (module docstring, step 3), or None and why not."""
        tokens = presented_tokens(scope, headers)
        if not tokens:
            return (OWNER_CALLER, "") if self.token is None else (None, NO_TOKEN)
        if self.token is not None:
            expected = self.token.encode()
            if any(secrets.compare_digest(t.encode(), expected) for t in tokens):
                return OWNER_CALLER, ""
        if self.identify is not None:
            for token in tokens:
                found = await anyio.to_thread.run_sync(self.identify, token)
                if found is not None:
                    return found, ""
        return None, BAD_TOKEN

    async def _limited(self, scope: Scope, receive: Receive, send: Send, untyped: bool) -> None:
        """Run the app, counting the body as it arrives; `untyped`: a body → 415."""
        received = 0
        started = False

        async def limited_receive() -> Message:
            nonlocal received
            message = await receive()
            if message["type"] == "http.request":
                chunk = len(message.get("body", b""))
                received += chunk
                if received > self.max_body_bytes:
                    raise _Refused(413, self._too_large())
                if untyped and chunk:
                    raise _Refused(415, f"send the body as {JSON_TYPE}; it names no Content-Type")
            return message

        async def tracking_send(message: Message) -> None:
            nonlocal started
            if message["type"] == "http.response.start":
                started = True
            await send(message)

        try:
            await self.app(scope, limited_receive, tracking_send)
        except _Refused as refused:
            if not started:
                await _send_error(send, refused.status_code, refused.detail, {})
