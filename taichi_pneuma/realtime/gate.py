"""The live page's guard on viser's websocket server: the token checked in the HTTP upgrade request, before the
websocket is accepted (a request without it, or with another, is answered 403 and no frame of it is ever read); a
message larger than MAX_MESSAGE bytes closes its connection (1009) before it is buffered whole; and each message is
handed to viser only once a check (the page's, realtime/web.py) has passed it, a refused one logged in one line (no
traceback) and dropped, the connection going on (MAX_REFUSED refused close it, so a client cannot flood the log); at
most MAX_CONNECTIONS websockets are open at once (503 past that). What the websockets library logs of a connection
(a request that is not HTTP, a handler's error) is one line too: the exception's type and message.

viser (1.1) starts its server with websockets.asyncio.server.serve inside ViserServer(), with its own
process_request (the page's files) and a 50 MB max_size, and has no parameter for either: guarded_serve wraps
that one function while a ViserServer starts, for viser's call only, and raises if viser did not call it (a
viser that serves otherwise would be unguarded: refused, not run).
"""

from __future__ import annotations

import contextlib
import functools
import http
import logging
import secrets
import threading
from collections.abc import Callable
from urllib.parse import parse_qs, urlsplit

import websockets.asyncio.server as ws_server
from websockets.datastructures import Headers
from websockets.http11 import Request, Response
from websockets.typing import Data

from ..errors import quoted

MAX_MESSAGE = 64 * 1024  # bytes a page's message may have (its largest, a camera pose, has about 300)
MAX_CONNECTIONS = 8  # open websockets with the token at once (each a browser tab): one more is answered 503
MAX_REFUSED = 10  # messages refused on one connection before it is closed (1008): the log stays bounded
log = logging.getLogger("taichi_pneuma.live")


class OneLine(logging.Filter):
    """A record with an exception, in one line: its message, then the exception's type and message (no
    traceback)."""

    def filter(self, record: logging.LogRecord) -> bool:
        if record.exc_info and record.exc_info[1] is not None:
            exc = record.exc_info[1]
            record.msg, record.args = f"live page: {record.getMessage()}: {type(exc).__name__}: {quoted(exc)}", None
            record.exc_info, record.exc_text = None, None
        return True


connections_log = logging.getLogger("taichi_pneuma.live.connections")  # the websockets library's, for viser's server
connections_log.addFilter(OneLine())
# one ViserServer started at a time through the wrapped serve: module-level as what it guards is, websockets' own
# serve, which guarded_serve replaces for the whole process while viser starts
_serve_lock = threading.Lock()


def token_of(path: str) -> str:
    """The token in a request's path ('/?token=...'), '' if none."""
    return parse_qs(urlsplit(path).query).get("token", [""])[0]


class GuardedConnection(ws_server.ServerConnection):
    """A websocket connection whose recv() returns only the messages refusal(message) passes (returns None
    for); a refused one is logged in one line with refusal's reason and skipped, and MAX_REFUSED of them in a row
    close the connection (1008)."""

    def __init__(self, *args, refusal: Callable[[Data], str | None], **kwargs):
        super().__init__(*args, **kwargs)
        self.refusal = refusal

    async def recv(self, decode: bool | None = None) -> Data:  # type: ignore[override]  # (the base overloads on decode)
        refused = 0
        while True:
            message = await super().recv(decode)
            reason = self.refusal(message)
            if reason is None:
                return message
            host, port = self.remote_address[:2]
            log.warning("live page: refused a message from %s port %s: %s", host, port, reason)
            refused += 1
            if refused >= MAX_REFUSED:
                log.warning(
                    "live page: closed the connection from %s port %s: %d messages refused", host, port, refused
                )
                await self.close(1008, "too many refused messages")


def upgrade_gate(token: str, files: Callable | None) -> Callable:
    """A process_request: viser's file server (files) answers what it serves; any request it would let through
    to the websocket upgrade is refused (403) unless its URL carries `token`, and (503) while MAX_CONNECTIONS
    websockets are open."""

    def gate(connection: ws_server.ServerConnection, request: Request) -> Response | None:
        answer = files(connection, request) if files is not None else None
        if answer is not None:
            return answer
        if not secrets.compare_digest(token_of(request.path), token):
            return Response(
                http.HTTPStatus.FORBIDDEN, "Forbidden", Headers(), b"this page needs the URL with its token\n"
            )
        if len(connection.server.connections) >= MAX_CONNECTIONS:
            return Response(
                http.HTTPStatus.SERVICE_UNAVAILABLE,
                "Service Unavailable",
                Headers(),
                f"{MAX_CONNECTIONS} pages are open on this scene already: close one\n".encode(),
            )
        return None

    return gate


@contextlib.contextmanager
def guarded_serve(token: str, refusal: Callable[[Data], str | None]):
    """While the block runs, viser's call of websockets.asyncio.server.serve gets upgrade_gate(token, its own
    process_request), max_size MAX_MESSAGE, GuardedConnection(refusal) connections and connections_log; other
    callers get serve as it is. Raises RuntimeError if the block ends without viser's call."""
    serve = ws_server.serve
    called = threading.Event()

    def guarded(handler, *args, **kwargs):
        if getattr(handler, "__module__", None) != "viser.infra._infra":
            return serve(handler, *args, **kwargs)
        called.set()
        kwargs["process_request"] = upgrade_gate(token, kwargs.get("process_request"))
        kwargs["max_size"] = MAX_MESSAGE
        kwargs["create_connection"] = functools.partial(GuardedConnection, refusal=refusal)
        kwargs["logger"] = connections_log
        return serve(handler, *args, **kwargs)

    with _serve_lock:
        setattr(ws_server, "serve", guarded)  # noqa: B010  (the library's function replaced: its signature differs)
        try:
            yield
        finally:
            setattr(ws_server, "serve", serve)  # noqa: B010
    if not called.is_set():
        raise RuntimeError("viser did not start its server through websockets.asyncio.server.serve: not guarded")
