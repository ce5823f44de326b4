"""The WebSocket of a live session: ``/ws/live/{session_id}/``.

A capture client (API token) or a browser (signed-in session) of the session's clinic connects;
anyone else is refused before the handshake completes. Every connection joins the session's
group: what one connection sends (frames, see `analysis.live.session`) is answered to it
directly and shown to the others (the live page), position events with both skeletons' poses.
A replay session streams its stored recording from the server through the same path.

Per session, the aligner state lives in this process (`SESSIONS`), so a capture client that
reconnects resumes where it stopped; with several server processes, route a session's
connections to one process (sticky sessions).

Events are broadcast to the group only while someone else watches the session: a connection of
the same session in this process (`CONNECTIONS`), or one in another process that said hello
through the channel layer. A capture client alone costs no channel-layer traffic (with Redis,
a round trip per event), which is most of what a server spends per frame besides the aligner.

A connection opened with ``?watch=1`` (the watch page of a therapist) only follows: it sends no
frames, and what it sends is refused. While frames arrive, the session's row records them
(`services.record_activity`: at each repetition, and at most every `ACTIVITY_EVERY` seconds
otherwise), so the therapist's home page lists the session while it runs.

A batch of frames (``{"type": "frames", ...}``, `analysis.live.session`) is answered with one
message, a JSON array of its events (none when it has none): the per-message cost of Daphne and
Channels, most of a frame's cost, is paid once per batch. JSON is read and written with orjson
when it is installed (a few times faster than the standard library on frames of numbers).

A batch may also come as a WebSocket binary message of float32 values (`analysis.live.frames`,
read with one `numpy.frombuffer`): it is answered the same way, a JSON array of its events. The
``ready`` event says which version of that form the server reads (``binary_frames``), so a
capture client sends binary frames only to a server that takes them; JSON frames keep working.
"""

from __future__ import annotations

import asyncio
import json
import logging
import time
from typing import Any
from urllib.parse import parse_qs

from channels.db import database_sync_to_async
from channels.generic.websocket import AsyncWebsocketConsumer
from django.conf import settings

from analysis.bvh import AnalysisInputError
from analysis.live import LiveSession as SessionState
from analysis.live import header_text
from analysis.live.frames import VERSION as BINARY_VERSION
from analysis.live.frames import decode_frames, take_frames
from analysis.live.session import ProtocolError, error_event
from webapp.live import camera, services
from webapp.live.auth import scope_user
from webapp.live.models import LiveSession, LiveStatus

try:
    import orjson
except ImportError:  # optional: the standard library does the same, slower
    orjson = None

log = logging.getLogger(__name__)
SESSIONS: dict[str, SessionState] = {}
CONNECTIONS: dict[str, int] = {}  # open connections per session in this process
MAX_MESSAGE_BYTES = 1 << 20
REFUSED = 4403
REPLAY_SPEED = 1.0  # times real time
ACTIVITY_EVERY = 5.0  # seconds between writes of "frames still arriving" to the session's row


def _error(code: str, message: str) -> dict[str, Any]:
    return {"event": "error", "code": code, "message": message, "seq": None}


def is_watcher(scope: dict[str, Any]) -> bool:
    query = parse_qs(scope.get("query_string", b"").decode("latin-1"))
    return query.get("watch", [""])[0] == "1"


class LiveConsumer(AsyncWebsocketConsumer):
    live: LiveSession
    replay: asyncio.Task[None] | None = None
    heard_other = False  # a connection of this session in another process said hello
    watching = False  # a read-only follower (the watch page)
    activity_at = float("-inf")  # when this connection last wrote the session's activity

    async def connect(self) -> None:
        session_id = str(self.scope["url_route"]["kwargs"]["session_id"])
        user = await scope_user(self.scope)
        live = (
            None
            if user is None
            else await database_sync_to_async(services.session_for)(user, session_id)
        )
        if live is None:
            await self.close(code=REFUSED)  # before accept: the handshake answers 403
            return
        self.user, self.live, self.key = user, live, str(live.pk)
        self.watching = is_watcher(self.scope)
        self.group = f"live-{self.key}"
        await self.channel_layer.group_add(self.group, self.channel_name)
        await self.accept()
        CONNECTIONS[self.key] = CONNECTIONS.get(self.key, 0) + 1
        await self.channel_layer.group_send(
            self.group, {"type": "live.hello", "origin": self.channel_name, "answer": True}
        )
        state = SESSIONS.get(self.key)
        if state is not None:
            await self.send_json(_ready(state.ready()))
        elif live.status == LiveStatus.ENDED:
            await self.send_json({**live.summary, "event": "summary"})
        elif live.replay_of_id is not None and not self.watching:
            self.replay = asyncio.create_task(self._replay())

    async def dispatch(self, message: dict[str, Any]) -> None:
        """Frames skip Channels' closing of stale database connections before every message (a
        hop to a worker thread and back, a tenth of what a batch of frames costs): the frame
        path touches the database only through `database_sync_to_async`, which closes them
        itself. Every other message goes through Channels' own dispatch."""
        if message["type"] == "websocket.receive":
            await self.websocket_receive(message)
        else:
            await super().dispatch(message)

    async def disconnect(self, code: int) -> None:
        if hasattr(self, "group"):
            await self.channel_layer.group_discard(self.group, self.channel_name)
            left = CONNECTIONS.get(self.key, 1) - 1
            if left > 0:
                CONNECTIONS[self.key] = left
            else:
                CONNECTIONS.pop(self.key, None)
        if self.replay is not None:
            self.replay.cancel()

    async def receive(self, text_data: str | None = None, bytes_data: bytes | None = None) -> None:
        received = time.perf_counter()
        content = text_data if text_data is not None else bytes_data
        if content is None or len(content) > MAX_MESSAGE_BYTES:
            text = "send messages under 1 MB: JSON text, or frames in binary form"
            await self.send_json(_error("bad-message", text))
            return
        if self.watching:
            await self.send_json(_error("read-only", "a watching connection sends nothing"))
            return
        if bytes_data is not None and text_data is None:
            await self.process_binary(bytes_data, received)
            return
        try:
            message = _loads(text_data)
        except ValueError:
            await self.send_json(_error("bad-json", "the message is not valid JSON"))
            return
        await self.process(message, received)

    async def process(self, message: Any, received: float) -> None:
        """Answer one JSON message: to this connection, and to the group's other connections."""
        state = await self._state_or_error()
        if state is not None and camera.is_camera_start(message):
            await self._answer(state, camera.start(self.key, state, message), received, batch=False)
        elif state is not None:
            batch = isinstance(message, dict) and message.get("type") == "frames"
            await self._answer(state, state.handle(message), received, batch=batch)

    async def process_binary(self, data: bytes, received: float) -> None:
        """Answer a batch of frames in binary form as a JSON batch is answered."""
        try:
            block = decode_frames(data)
        except ProtocolError as error:
            await self.send_json(error_event(error))
            return
        # the session's state, made at its first message (the await only then)
        state = SESSIONS.get(self.key) or await self._state_or_error()
        stream = camera.CAMERAS.get(self.key)
        if state is not None and stream is not None:  # landmarks from the camera page
            events = camera.take(state, stream, block)
            camera.with_reference(state, events)
            await self._answer(state, events, received, batch=True)
        elif state is not None:
            await self._answer(state, take_frames(state, block), received, batch=True)

    async def _answer(
        self, state: SessionState, events: list[dict[str, Any]], received: float, *, batch: bool
    ) -> None:
        """Send a message's events (a batch's in one JSON array), show them to the group."""
        repetitions, summary = _stamped(state, events, received)
        if summary is not None:
            await self._finish(state, summary)
        if batch:
            if events:
                await self.send(text_data=_dumps(events))
        else:
            for event in events:
                await self.send_json(event)
        if self.watched():
            for event in events:
                await self._broadcast(state, event)
        now = time.monotonic()
        if repetitions is not None or now - self.activity_at >= ACTIVITY_EVERY:
            await self._note_activity(now, repetitions)

    async def _note_activity(self, now: float, repetitions: int | None) -> None:
        """Write that frames are arriving: at once for a new repetition, otherwise at most
        every `ACTIVITY_EVERY` seconds (not a database write per frame; `_answer` decides)."""
        self.activity_at = now
        await database_sync_to_async(services.record_activity)(self.key, repetitions)

    async def _state_or_error(self) -> SessionState | None:
        """The session's state (made at its first message), or None after answering with an
        error when the exercise's model cannot be had."""
        try:
            return await self._state()
        except services.SessionEndedError as error:
            await self.send_json(_error("ended", str(error)))
            return None
        except (AnalysisInputError, ValueError) as error:
            await self.send_json(_error("bad-header", " ".join(str(error).split())))
            return None

    async def _state(self) -> SessionState:
        state = SESSIONS.get(self.key)
        if state is None:
            # an ended session stays ended: frames sent to it again would re-open it and store
            # a second recording under the first one's name
            await database_sync_to_async(services.refuse_if_ended)(self.key)
            model = await database_sync_to_async(services.exercise_model)(self.live.exercise)
            options = await database_sync_to_async(services.session_options)(self.live)
            made = SessionState(
                model, max_fps=settings.LIVE_MAX_FPS, burst=settings.LIVE_BURST, options=options
            )
            state = SESSIONS.setdefault(self.key, made)
            await database_sync_to_async(services.mark_live)(self.live)
        return state

    async def _finish(self, state: SessionState, closing: dict[str, Any]) -> dict[str, Any]:
        """Store the frames as a Recording (the pipeline analyses it) and end the session;
        ``closing`` is the session's summary event, completed here."""
        lat = sorted(state.delivery_ms)
        if lat:
            closing["latency_ms_p95"] = lat[min(len(lat) - 1, int(0.95 * len(lat)))]
        stream = camera.forget(self.key)
        if stream is not None:  # the camera's landmarks are the recording (a MediaPipe file)
            recording = await database_sync_to_async(services.store_landmarks)(
                self.live, stream.recording_json(), len(stream.landmarks), self.user
            )
        else:
            recording = await database_sync_to_async(services.store_frames)(
                self.live, state.bvh(), self.user
            )
        closing["recording"] = None if recording is None else str(recording.pk)
        await database_sync_to_async(services.finish)(self.live, closing, recording)
        SESSIONS.pop(self.key, None)
        return closing

    def watched(self) -> bool:
        """Is another connection of this session open (here, or in another process)?"""
        return CONNECTIONS.get(self.key, 0) > 1 or self.heard_other

    async def _broadcast(self, state: SessionState, event: dict[str, Any]) -> None:
        """Show one event to the session's other connections (`_answer` calls this only while
        someone watches)."""
        if event["event"] == "position" and state.aligner is not None:
            poses = state.aligner.poses()
            if poses is not None:
                parents = state.model.tutor.skeleton.parents.tolist()
                event = {**event, "patient": _flat(poses[0]), "tutor": _flat(poses[1]),
                         "parents": parents}  # fmt: skip
        message = {"type": "live.event", "event": event, "origin": self.channel_name}
        await self.channel_layer.group_send(self.group, message)

    async def live_event(self, message: dict[str, Any]) -> None:
        if message.get("origin") != self.channel_name:
            await self.send_json(message["event"])

    async def live_hello(self, message: dict[str, Any]) -> None:
        """Another connection joined the session: from now on events are broadcast; it is
        answered, so that it knows too."""
        if message.get("origin") == self.channel_name:
            return
        self.heard_other = True
        if message.get("answer"):
            await self.channel_layer.group_send(
                self.group, {"type": "live.hello", "origin": self.channel_name, "answer": False}
            )

    async def send_json(self, content: dict[str, Any]) -> None:
        await self.send(text_data=_dumps(content))

    async def _replay(self) -> None:
        """Stream the stored recording at real time through the live path."""
        try:
            motion = await database_sync_to_async(services.replay_motion)(self.live)
            start = {"type": "start", "header": header_text(motion)}
            await self.process(start, time.perf_counter())
            begin = time.perf_counter()
            for seq, values in enumerate(motion.frames):
                delay = begin + seq * motion.frame_time / REPLAY_SPEED - time.perf_counter()
                await asyncio.sleep(max(0.0, delay))
                frame = {"type": "frame", "seq": seq, "values": values.tolist()}
                await self.process(frame, time.perf_counter())
            await self.process({"type": "end"}, time.perf_counter())
        except asyncio.CancelledError:
            raise
        except Exception:  # a replay must never take the server down
            log.exception("replay of live session %s failed", self.key)
            await self.send_json(_error("replay-failed", "the replay stopped"))


def _stamped(
    state: SessionState, events: list[dict[str, Any]], received: float
) -> tuple[int | None, dict[str, Any] | None]:
    """A message's events made ready to send, in one pass: each position event's time in the
    consumer, the binary form a ``ready`` event's server reads; returned: the newest
    repetition's count (None: the message ended none) and the ``summary`` event, if any."""
    repetitions = summary = None
    for event in events:
        kind = event["event"]
        if kind == "position":
            event["latency_ms"] = round((time.perf_counter() - received) * 1000.0, 3)
            state.delivery_ms.append(event["latency_ms"])
        elif kind == "repetition":
            repetitions = int(event["index"]) + 1
        elif kind == "summary":
            summary = event
        elif kind == "ready":
            _ready(event)
    return repetitions, summary


def _ready(event: dict[str, Any]) -> dict[str, Any]:
    """A ``ready`` event, with the version of binary frames this server reads."""
    event["binary_frames"] = BINARY_VERSION
    return event


def _loads(text: str) -> Any:
    if orjson is not None:
        try:
            return orjson.loads(text)
        except orjson.JSONDecodeError:
            pass  # the standard library also reads NaN and Infinity, which then get their error
    return json.loads(text)


def _dumps(content: Any) -> str:
    if orjson is not None:
        return orjson.dumps(content, option=orjson.OPT_SERIALIZE_NUMPY).decode()
    return json.dumps(content, separators=(",", ":"))


def _flat(points: Any) -> list[float]:
    return [round(float(v), 1) for v in points.reshape(-1)]
