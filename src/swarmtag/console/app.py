"""The console's HTTP layer (Starlette): routes, the token check, the event stream, the page.

Thin on purpose: every answer comes from ``ConsoleCore``; this module only
checks who is asking (``swarmtag.console.auth``), reads at most
``MAX_BODY + 1`` bytes of a write, and turns ``Reply`` into JSON. The
source (a simulation, a replay, a scanner) is advanced by a background
task in the app's lifespan, in a worker thread, so requests are never held
up by a tick; writes run in a worker thread too (a GATT write waits on the
radio).
"""

from __future__ import annotations

import asyncio
import functools
import json
import time
from collections.abc import AsyncIterator, Awaitable, Callable
from contextlib import asynccontextmanager
from importlib.resources import files
from typing import Any, Final

import anyio.to_thread
from starlette.applications import Starlette
from starlette.requests import Request
from starlette.responses import (
    HTMLResponse,
    JSONResponse,
    RedirectResponse,
    Response,
    StreamingResponse,
)
from starlette.routing import Route

from swarmtag.console.api import MAX_BODY, ConsoleCore, Reply
from swarmtag.console.auth import COOKIE, WRITE_HEADER, token_matches

__all__ = ["STATIC", "STEP_S", "STREAM_S", "make_app"]

STEP_S: Final = 0.05
"""Seconds between the stepping task's advances (20 a second)."""
STREAM_S: Final = 0.1
"""Seconds between an event stream's ``state`` events (10 updates a second)."""
STATIC: Final = {
    "console.js": "text/javascript; charset=utf-8",
    "console.css": "text/css; charset=utf-8",
}
"""The page's assets, shipped in swarmtag/console/static (no build step, no CDN)."""
_BEAT_S: Final = 0.05
"""Seconds between an event stream's looks at whether the server is stopping."""
_SECURITY_HEADERS: Final = {
    "Content-Security-Policy": "default-src 'self'; img-src 'self' data:; frame-ancestors 'none'",
    "X-Content-Type-Options": "nosniff",
    "Referrer-Policy": "no-referrer",
    "Cache-Control": "no-store",
}
_LOCKED_OUT: Final = (
    "<!doctype html><title>swarmtag console</title><p>Open the URL that "
    "<code>swarmtag console</code> printed (it carries the token), or send "
    "<code>Authorization: Bearer TOKEN</code>.</p>"
)

_Handler = Callable[[Request], Awaitable[Response]]


def _asset(name: str) -> bytes:
    return files("swarmtag.console").joinpath("static", name).read_bytes()


def _json(reply: Reply) -> JSONResponse:
    return JSONResponse(reply.body, status_code=reply.status, headers=_SECURITY_HEADERS)


def _bearer(request: Request) -> str | None:
    scheme, _, value = request.headers.get("authorization", "").partition(" ")
    return value.strip() if scheme.lower() == "bearer" else None


def _never() -> bool:
    return False


def make_app(
    core: ConsoleCore,
    token: str,
    *,
    stream_s: float = STREAM_S,
    stopping: Callable[[], bool] = _never,
) -> Starlette:
    """The ASGI app serving ``core`` to holders of ``token``; events every ``stream_s``.

    Event streams end by themselves once ``stopping()`` is true (the server's
    shutdown has begun), so that Ctrl-C need not cut them.
    """

    def who(request: Request) -> tuple[str, str] | None:
        """(how, client) if the request holds the token, else None."""
        host = request.client.host if request.client else "unknown"
        if token_matches(_bearer(request), token):
            return "bearer", host
        if token_matches(request.cookies.get(COOKIE), token):
            return "cookie", host
        return None

    def guarded(handler: Callable[[Request, str], Awaitable[Response]]) -> _Handler:
        async def check(request: Request) -> Response:
            found = who(request)
            if found is None:
                return _json(Reply(401, {"error": "no valid token: send Authorization: Bearer"}))
            return await handler(request, f"{found[1]} ({found[0]})")

        return check

    async def page(request: Request) -> Response:
        given = request.query_params.get("token")
        if given is not None:
            if not token_matches(given, token):
                return HTMLResponse(_LOCKED_OUT, status_code=401, headers=_SECURITY_HEADERS)
            response = RedirectResponse("/", status_code=303, headers=_SECURITY_HEADERS)
            response.set_cookie(COOKIE, token, httponly=True, samesite="strict", path="/")
            return response
        if who(request) is None:
            return HTMLResponse(_LOCKED_OUT, status_code=401, headers=_SECURITY_HEADERS)
        return HTMLResponse(_asset("index.html"), headers=_SECURITY_HEADERS)

    async def static(request: Request) -> Response:
        name = request.path_params["name"]
        if name not in STATIC:
            return Response("not found", status_code=404)
        return Response(_asset(name), media_type=STATIC[name], headers=_SECURITY_HEADERS)

    async def tags(request: Request, _who: str) -> Response:
        return _json(core.tags())

    async def kpis(request: Request, _who: str) -> Response:
        return _json(await anyio.to_thread.run_sync(core.kpis))

    async def floor(request: Request, _who: str) -> Response:
        return _json(core.floor())

    async def state(request: Request, _who: str) -> Response:
        return _json(Reply(200, core.state()))

    async def eink(request: Request, _who: str) -> Response:
        answer = await anyio.to_thread.run_sync(core.eink, request.path_params["marker"])
        if isinstance(answer, Reply):
            return _json(answer)
        return Response(answer, media_type="image/png", headers=_SECURITY_HEADERS)

    async def write(request: Request, caller: str) -> Response:
        if _bearer(request) is None and WRITE_HEADER not in request.headers:
            return _json(_no_header())
        body = await _body(request)
        # in a worker thread: a write over the radio (--scan) runs its own event loop
        reply = await anyio.to_thread.run_sync(
            functools.partial(
                core.write,
                who=caller,
                client=request.client.host if request.client else "unknown",
                marker=request.path_params["marker"],
                field=request.path_params["field"],
                body=body,
            )
        )
        return _json(reply)

    async def replay(request: Request, _who: str) -> Response:
        if _bearer(request) is None and WRITE_HEADER not in request.headers:
            return _json(_no_header())
        return _json(core.control(await _body(request)))

    async def events(request: Request, _who: str) -> Response:
        return StreamingResponse(
            _stream(core, stream_s, stopping),
            media_type="text/event-stream",
            headers={**_SECURITY_HEADERS, "X-Accel-Buffering": "no"},
        )

    @asynccontextmanager
    async def lifespan(_app: Starlette) -> AsyncIterator[None]:
        task = asyncio.create_task(_stepping(core))
        try:
            yield
        finally:
            task.cancel()

    routes = [
        Route("/", page),
        Route("/static/{name}", static),
        Route("/api/tags", guarded(tags)),
        Route("/api/kpis", guarded(kpis)),
        Route("/api/floor", guarded(floor)),
        Route("/api/state", guarded(state)),
        Route("/api/events", guarded(events)),
        Route("/api/tags/{marker}/eink", guarded(eink)),
        Route("/api/replay", guarded(replay), methods=["POST"]),
        Route("/api/tags/{marker}/{field}", guarded(write), methods=["POST"]),
    ]
    return Starlette(routes=routes, lifespan=lifespan)


def _no_header() -> Reply:
    return Reply(403, {"error": f"a write with the cookie needs the {WRITE_HEADER} header"})


async def _body(request: Request) -> bytes:
    """The request's body, read no further than ``MAX_BODY + 1`` bytes."""
    body = bytearray()
    async for chunk in request.stream():
        body += chunk
        if len(body) > MAX_BODY:
            break
    return bytes(body)


async def _stepping(core: ConsoleCore) -> None:
    """Advance the source by the wall time that passed, ``STEP_S`` apart, in a worker thread."""
    then = time.monotonic()
    while True:
        await asyncio.sleep(STEP_S)
        now = time.monotonic()
        await anyio.to_thread.run_sync(core.source.advance, now - then)
        then = now


def _event(kind: str, data: Any) -> str:  # noqa: ANN401 - any JSON value
    return f"event: {kind}\ndata: {json.dumps(data, separators=(',', ':'))}\n\n"


async def _stream(
    core: ConsoleCore, every: float, stopping: Callable[[], bool]
) -> AsyncIterator[str]:
    """Server-sent events: ``state`` every ``every`` seconds, ``kpis`` about once a second.

    The events keep to a fixed schedule (the time a snapshot takes does not
    stretch the interval; a stream that fell behind skips ahead rather than
    bursting). Snapshots are taken and encoded in a worker thread, so the
    event loop never waits for the source's lock while a tick is stepped.
    Starlette ends the stream when the client goes away; the server, by ``stopping``.
    """
    last_kpis = 0.0
    due = time.monotonic()
    while not stopping():
        yield await anyio.to_thread.run_sync(_state_event, core)
        now = time.monotonic()
        if now - last_kpis >= 1.0:
            last_kpis = now
            yield _event("kpis", (await anyio.to_thread.run_sync(core.kpis)).body)
        due = max(due + every, time.monotonic() - every)
        while not stopping() and time.monotonic() < due:
            await asyncio.sleep(min(_BEAT_S, max(due - time.monotonic(), 0.0)))


def _state_event(core: ConsoleCore) -> str:
    return _event("state", core.state())
