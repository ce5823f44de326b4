"""The camera page's sessions on the server: the browser sends MediaPipe world landmarks (binary
frames of `analysis.live.camera.VALUES_PER_FRAME` values), turned here into the exercise skeleton's
frames of the same `analysis.live.LiveSession` the capture client feeds (same aligner, same words).

A camera session starts with ``{"type": "start", "source": "camera", "fps": 15}`` instead of a BVH
header: the skeleton is fitted to the person on the first frames that show every needed body
part, and the session's own start is made with it then. Per session the conversion lives in this
process (`CAMERAS`), beside the consumer's `SESSIONS`, so a browser that reconnects resumes.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from analysis.live import LiveSession as SessionState
from analysis.live.camera import CameraFrameError, CameraStream
from analysis.live.frames import FrameBlock, take_frames
from analysis.live.session import ProtocolError, error_event
from analysis.live.words import Event

CAMERAS: dict[str, CameraStream] = {}


def is_camera_start(message: Any) -> bool:
    return (
        isinstance(message, dict)
        and message.get("type") == "start"
        and message.get("source") == "camera"
    )


def start(key: str, state: SessionState, message: dict[str, Any]) -> list[Event]:
    """Answer a camera session's start: ready (a reconnect resumes at its next frame)."""
    if key not in CAMERAS:
        try:
            CAMERAS[key] = CameraStream(
                float(message.get("fps") or 0.0), state.model.tutor.skeleton
            )
        except (CameraFrameError, TypeError, ValueError):
            text = "'start' from a camera needs its frame rate ('fps', 1 to 120)"
            return [error_event(ProtocolError("bad-header", text))]
    return [{**state.ready(), "camera": True}]


def take(state: SessionState, camera: CameraStream, block: FrameBlock) -> list[Event]:
    """Events answering one binary message of landmarks (never raises for bad input)."""
    try:
        events: list[Event] = []
        if state.motion is None:
            header = camera.header(block.values)
            if header is None:
                text = "the whole body the exercise needs is not in view yet"
                raise ProtocolError("not-in-view", text, block.seq)
            events = state.handle({"type": "start", "header": header})
        first = max(block.seq, state.next_seq)
        fresh = block.values[first - block.seq :]
        if fresh.shape[0] == 0:
            return [*events, *take_frames(state, block_of(block.seq, block.values, state))]
        before = state.next_seq
        values = camera.channels(fresh)
        answered = take_frames(state, FrameBlock(first, values))
        refused = {e["seq"] for e in answered if e["event"] == "error"}
        kept = [k for k in range(fresh.shape[0]) if before + k not in refused]
        camera.keep(fresh[kept])
        return [*events, *answered]
    except CameraFrameError as error:
        state.errors += 1
        return [error_event(ProtocolError("camera-frame", str(error), block.seq))]
    except ProtocolError as error:
        state.errors += 1
        return [error_event(error)]


def block_of(seq: int, values: np.ndarray, state: SessionState) -> FrameBlock:
    """A block already received (a resend after a reconnect): the session answers it as a
    duplicate; its values' count is the skeleton's so that the answer says only that."""
    channels = state.aligner.n_channels if state.aligner is not None else values.shape[1]
    return FrameBlock(seq, np.zeros((values.shape[0], channels)))


def with_reference(state: SessionState, events: list[Event]) -> None:
    """The demonstration's pose (kept in step) on the batch's last position event: the camera
    page draws it small beside the picture."""
    positions = [e for e in events if e["event"] == "position"]
    if not positions or state.aligner is None:
        return
    poses = state.aligner.poses()
    if poses is not None:
        positions[-1]["tutor"] = [round(float(v), 1) for v in poses[1].reshape(-1)]
        positions[-1]["parents"] = state.model.tutor.skeleton.parents.tolist()


def forget(key: str) -> CameraStream | None:
    return CAMERAS.pop(key, None)
