"""The server side of ``python -m analysis stream --server``: create a live session over HTTP,
stream the frames over its WebSocket, print the events, resume after a dropped connection.

Frames carry sequence numbers; on (re)connecting, the server's ``ready`` event says which frame
it expects next, and the client resends from there, so a reconnect loses nothing. The client
keeps under the ``max_fps`` the server announces, so ``--speed max`` is never rate-limited.

Frames go in batches of up to ``batch`` (one message, ``{"type": "frames", ...}``): the server's
cost is mostly per message. A batch waits at most `BATCH_WAIT` for its frames, so batching adds
at most that to a frame's latency; by default a batch holds the frames a source sends in that
time (3 at 120 frames/s, 1 at 30).

A batch goes as a WebSocket binary message of float32 values (`analysis.live.frames`), which
costs the server less to read than JSON, when the server's ``ready`` event says it reads that
form (``binary_frames``); the values are then float32 (7 significant digits, what the stored
recording holds). To a server that does not say so (an older one) a batch goes as JSON text, the
same frames. The fallback is automatic, decided again at each (re)connection; ``stream_to``
takes ``binary=False`` to send JSON regardless.
"""

from __future__ import annotations

import asyncio
import json
import sys
import threading
import urllib.error
import urllib.parse
import urllib.request
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt
from websockets.asyncio.client import ClientConnection, connect
from websockets.exceptions import ConnectionClosed, InvalidStatus, InvalidURI

from analysis.live import Event
from analysis.live.frames import VERSION as BINARY_VERSION
from analysis.live.frames import encode_frames
from capture.sources import Source, StreamInputError, print_event

FloatArray = npt.NDArray[np.float64]
RETRIES = 6
SEND_SHARE = 0.8  # of the server's max_fps
BATCH_WAIT = 0.025  # seconds the first frame of a batch may wait for the others
MAX_BATCH = 64  # as the server takes (analysis.live.session)


def default_batch(frame_time: float) -> int:
    """Frames a source sends in `BATCH_WAIT` (at least 1)."""
    if not frame_time > 0:
        return 1
    return max(1, min(MAX_BATCH, int(BATCH_WAIT / frame_time + 1e-9)))


@dataclass
class Buffer:
    """Frames read so far (kept for resending) and whether the source has ended."""

    frames: list[FloatArray] = field(default_factory=list)
    done: bool = False
    error: BaseException | None = None
    printed: dict[str, int] = field(default_factory=dict)  # newest frame / repetition printed
    changed: asyncio.Event = field(default_factory=asyncio.Event)


def _post_json(url: str, token: str, body: dict[str, Any]) -> dict[str, Any]:
    request = urllib.request.Request(
        url,
        data=json.dumps(body).encode(),
        headers={"Authorization": f"Token {token}", "Content-Type": "application/json"},
        method="POST",
    )
    with urllib.request.urlopen(request, timeout=30) as response:
        return dict(json.loads(response.read()))


def create_session(server: str, token: str, patient: str, exercise: str) -> dict[str, Any]:
    """POST /api/v1/live-sessions/ -> {"id", "ws"}; StreamInputError when refused."""
    if urllib.parse.urlsplit(server).scheme not in ("http", "https"):
        raise StreamInputError(f"--server takes http://HOST:PORT, got {server!r}")
    url = server.rstrip("/") + "/api/v1/live-sessions/"
    try:
        return _post_json(url, token, {"patient": patient, "exercise": exercise})
    except urllib.error.HTTPError as error:
        if error.code in (401, 403):
            raise StreamInputError("the server refused the token") from None
        detail = error.read(2000).decode(errors="replace")
        message = f"the server answered {error.code}: {' '.join(detail.split())}"
        raise StreamInputError(message) from None
    except (urllib.error.URLError, OSError) as error:
        raise StreamInputError(f"cannot reach {server}: {error}") from None


def watch_url(server: str, session_id: str) -> str:
    """Where a therapist of the clinic follows the session in a browser while it runs."""
    return f"{server.rstrip('/')}/live/{session_id}/watch/"


def ws_url(server: str, path: str) -> str:
    parts = urllib.parse.urlsplit(server)
    scheme = "wss" if parts.scheme == "https" else "ws"
    return f"{scheme}://{parts.netloc}{path}"


def _produce(source: Source, buffer: Buffer, loop: asyncio.AbstractEventLoop) -> None:
    """Read the source (it may block: pacing, TCP) in a thread, waking the sender per frame."""
    try:
        for frame in source.frames:
            buffer.frames.append(frame)
            loop.call_soon_threadsafe(buffer.changed.set)
    except (OSError, ValueError) as error:
        buffer.error = error
    finally:
        buffer.done = True
        loop.call_soon_threadsafe(buffer.changed.set)


async def _next_frame(buffer: Buffer, seq: int) -> FloatArray | None:
    while seq >= len(buffer.frames):
        if buffer.done:
            if buffer.error is not None:
                raise StreamInputError(str(buffer.error))
            return None
        buffer.changed.clear()
        if seq < len(buffer.frames) or buffer.done:
            continue
        await buffer.changed.wait()
    return buffer.frames[seq]


async def _next_batch(buffer: Buffer, seq: int, size: int) -> list[FloatArray]:
    """Frames from ``seq``: up to ``size``, those that come within `BATCH_WAIT` of the first
    (none: the source has ended)."""
    first = await _next_frame(buffer, seq)
    if first is None:
        return []
    batch = [first]
    deadline = asyncio.get_running_loop().time() + BATCH_WAIT
    while len(batch) < size:
        if seq + len(batch) >= len(buffer.frames):
            left = deadline - asyncio.get_running_loop().time()
            if left <= 0 or buffer.done:
                break
            try:
                await asyncio.wait_for(_next_frame(buffer, seq + len(batch)), left)
            except TimeoutError:
                break
            continue
        batch.append(buffer.frames[seq + len(batch)])
    return batch


def _message(seq: int, batch: list[FloatArray], binary: bool) -> str | bytes:
    if binary:
        return encode_frames(seq, np.vstack(batch))
    if len(batch) == 1:
        return json.dumps({"type": "frame", "seq": seq, "values": batch[0].tolist()})
    return json.dumps({"type": "frames", "seq": seq, "frames": [f.tolist() for f in batch]})


def _is_new(event: Event, printed: dict[str, int]) -> bool:
    """False for an event already printed (a server that lost the session after a restart
    aligns the resent frames again)."""
    key = {"position": "frame", "repetition": "index"}.get(str(event.get("event")))
    if key is None:
        return True
    value = int(event.get(key, -1))
    if value <= printed.get(key, -1):
        return False
    printed[key] = value
    return True


async def _receive(
    ws: ClientConnection, summary: asyncio.Future[Event], printed: dict[str, int]
) -> None:
    async for raw in ws:
        decoded = json.loads(raw)
        for event in decoded if isinstance(decoded, list) else [decoded]:  # a batch's events
            if _is_new(event, printed):
                print_event(event)
            if event.get("event") == "summary" and not summary.done():
                summary.set_result(event)
                return


async def _ready(ws: ClientConnection, header: str) -> Event:
    await ws.send(json.dumps({"type": "start", "header": header}))
    while True:
        event = json.loads(await ws.recv())
        if event.get("event") == "ready":
            return dict(event)
        if event.get("event") == "error":
            raise StreamInputError(f"the session refused the stream: {event.get('message')}")


async def _session(
    ws: ClientConnection, source: Source, buffer: Buffer, batch: int, binary: bool
) -> Event:
    """One connection: start (or resume), send the frames (in binary form if the server reads
    it and ``binary``), end, wait for the summary."""
    ready = await _ready(ws, source.header)
    binary = binary and ready.get("binary_frames") == BINARY_VERSION
    gap = 1.0 / (SEND_SHARE * float(ready.get("max_fps") or 1000.0))
    summary: asyncio.Future[Event] = asyncio.get_running_loop().create_future()
    reader = asyncio.create_task(_receive(ws, summary, buffer.printed))
    seq = int(ready["next_seq"])
    loop = asyncio.get_running_loop()
    try:
        while frames := await _next_batch(buffer, seq, batch):
            sent = loop.time()
            await ws.send(_message(seq, frames, binary))
            seq += len(frames)
            if (wait := sent + gap * len(frames) - loop.time()) > 0:
                await asyncio.sleep(wait)
        await ws.send(json.dumps({"type": "end"}))
        return await asyncio.wait_for(summary, timeout=120)
    finally:
        reader.cancel()


async def stream_to(
    url: str, token: str, source: Source, batch: int | None = None, *, binary: bool = True
) -> Event:
    """Stream the source to the live session at ``url`` in batches of up to ``batch`` frames
    (None: `default_batch`), in binary form when the server reads it (unless not ``binary``);
    the summary event."""
    size = default_batch(source.frame_time) if batch is None else max(1, min(MAX_BATCH, batch))
    buffer = Buffer()
    loop = asyncio.get_running_loop()
    threading.Thread(target=_produce, args=(source, buffer, loop), daemon=True).start()
    headers = {"Authorization": f"Token {token}"}
    for attempt in range(RETRIES + 1):
        try:
            async with connect(url, additional_headers=headers, max_size=1 << 22) as ws:
                return await _session(ws, source, buffer, size, binary)
        except InvalidStatus as error:
            code = error.response.status_code
            raise StreamInputError(f"the server refused the live session ({code})") from None
        except (ConnectionClosed, OSError, TimeoutError) as error:
            if attempt == RETRIES:
                raise StreamInputError(f"lost the connection to the server: {error}") from None
            await asyncio.sleep(min(0.2 * 2**attempt, 3.0))
    raise StreamInputError("lost the connection to the server")


def run_remote(
    server: str,
    token: str,
    patient: str,
    exercise: str,
    source: Source,
    *,
    batch: int | None = None,
    session: str | None = None,
) -> int:
    """Create the session (or join ``session``, one a therapist started on the patient's page),
    stream, print the events; 0 on success. The watch page's address goes to stderr: stdout
    holds only the JSON lines of the interface contract (README, "Command line")."""
    if session is None:
        created = create_session(server, token, patient, exercise)
    else:
        created = {"id": session, "ws": f"/ws/live/{urllib.parse.quote(session)}/"}
    print(f"Watch this session at {watch_url(server, str(created['id']))}", file=sys.stderr)
    try:
        asyncio.run(stream_to(ws_url(server, str(created["ws"])), token, source, batch))
    except InvalidURI as error:
        raise StreamInputError(str(error)) from None
    return 0
