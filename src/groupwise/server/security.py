"""The app's guards (docs/app.md, "Security").

For every HTTP request, in this order:

1. **Host**: Starlette's `TrustedHostMiddleware`, configured by `trusted_hosts`: with
   `allowed_hosts`, a Host header naming anything else → 400 (plain text "Invalid host
   header"). A loopback server thereby refuses pages that reach it through DNS rebinding (a
   foreign name resolving to 127.0.0.1): without CORS a foreign page cannot read the
   answers, but could still send requests.
2. **Token** (`GuardMiddleware`): with a token, every ``/api`` and ``/clips`` request needs
   ``Authorization: Bearer <token>`` or ``?token=<token>`` (for ``<video src>``) → else 401.
   Compared in constant time. The built web UI's files stay public (they hold no data).
3. **Body size** (`GuardMiddleware`): a body over `max_body_bytes` → 413, whether announced
   by Content-Length or streamed in chunks (counted as it arrives).

No CORS headers are ever added.
"""

import json
import secrets
from urllib.parse import parse_qs

from starlette.datastructures import Headers
from starlette.exceptions import HTTPException
from starlette.types import ASGIApp, Message, Receive, Scope, Send

PROTECTED_PREFIXES = ("/api", "/clips")


class _BodyTooLarge(HTTPException):
    """Raised from `receive`: FastAPI passes HTTP exceptions on (others become 400s)."""


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


class GuardMiddleware:
    """Token check and body limit (module docstring); the Host check is Starlette's."""

    def __init__(self, app: ASGIApp, *, token: str | None, max_body_bytes: int) -> None:
        self.app = app
        self.token = token
        self.max_body_bytes = max_body_bytes

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        headers = Headers(scope=scope)
        if self.token is not None and scope["path"].startswith(PROTECTED_PREFIXES):
            if not self._authorised(scope, headers):
                await _send_error(
                    send,
                    401,
                    "a token is required: send Authorization: Bearer <token> or ?token=",
                    {"www-authenticate": "Bearer"},
                )
                return
        length = headers.get("content-length")
        if length is not None and (not length.isdigit() or int(length) > self.max_body_bytes):
            await _send_error(send, 413, self._too_large(), {})
            return
        await self._limited(scope, receive, send)

    def _too_large(self) -> str:
        return f"the request body is larger than {self.max_body_bytes // 1024} KiB"

    def _authorised(self, scope: Scope, headers: Headers) -> bool:
        assert self.token is not None
        expected = self.token.encode()
        header = headers.get("authorization", "")
        if header[:7].lower() == "bearer " and secrets.compare_digest(
            header[7:].strip().encode(), expected
        ):
            return True
        query = parse_qs(scope.get("query_string", b"").decode("latin-1"))
        return any(secrets.compare_digest(v.encode(), expected) for v in query.get("token", []))

    async def _limited(self, scope: Scope, receive: Receive, send: Send) -> None:
        received = 0
        started = False

        async def limited_receive() -> Message:
            nonlocal received
            message = await receive()
            if message["type"] == "http.request":
                received += len(message.get("body", b""))
                if received > self.max_body_bytes:
                    raise _BodyTooLarge(413, self._too_large())
            return message

        async def tracking_send(message: Message) -> None:
            nonlocal started
            if message["type"] == "http.response.start":
                started = True
            await send(message)

        try:
            await self.app(scope, limited_receive, tracking_send)
        except _BodyTooLarge:
            if not started:
                await _send_error(send, 413, self._too_large(), {})
