"""Live frames in binary form: a batch of frames as little-endian float32 in one WebSocket
binary message, beside the JSON messages of `analysis.live.session` (which old clients keep
sending). Reading it is one `numpy.frombuffer`, with no Python work per value.

One message, 12 bytes of header then the values, every field little-endian:

    offset  size              field
    0       3                 magic, the bytes ``LVF``
    3       1                 version, 1
    4       2                 uint16: frames in the message, 1 to `MAX_BATCH`
    6       2                 uint16: values per frame (the skeleton's channels, as in the BVH
                              header the session's ``start`` message carried)
    8       4                 uint32: ``seq`` of the first frame; the others follow it (seq+1, ...)
    12      4 × frames × values   float32 values, frame after frame, in the header's channel order

It means what the JSON batch ``{"type": "frames", "seq": seq, "frames": [...]}`` means, with the
same rules (`take_frames`): a frame with a value that is not finite gets its error and uses up
its sequence number, a batch after the next expected frame is refused whole, frames already
received are skipped with one ``duplicate`` error, the rate limit drops frames. A message whose
values per frame differ from the skeleton's is refused whole (all its frames share the count,
so none of them could be taken). float32 keeps about 7 significant digits: 0.0001° on angles
and 0.001 cm on positions under 100 m, finer than any capture system measures.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from analysis.live.session import MAX_BATCH, LiveSession, ProtocolError, error_event
from analysis.live.words import Event

FloatArray = npt.NDArray[np.float64]
MAGIC = b"LVF"
VERSION = 1
HEADER = struct.Struct("<3sBHHI")  # magic, version, frames, values per frame, first seq
VALUE = np.dtype("<f4")


@dataclass(frozen=True)
class FrameBlock:
    """The frames of one binary message: ``values`` (frames, channels) float64, the first
    frame's sequence number ``seq``."""

    seq: int
    values: FloatArray


def encode_frames(seq: int, frames: npt.ArrayLike) -> bytes:
    """One binary message holding ``frames`` ((frames, channels) or one frame (channels,))
    from sequence number ``seq``; ValueError for what the format cannot hold."""
    values = np.atleast_2d(np.asarray(frames, dtype=VALUE))
    count, channels = values.shape if values.ndim == 2 else (0, 0)
    if not 0 < count <= MAX_BATCH or not 0 < channels <= 0xFFFF:
        raise ValueError(f"a message holds 1 to {MAX_BATCH} frames of 1 to 65535 values")
    if not 0 <= seq <= 0xFFFFFFFF:
        raise ValueError(f"seq must be 0 to 4294967295, got {seq}")
    return HEADER.pack(MAGIC, VERSION, count, channels, seq) + values.tobytes()


def decode_frames(data: bytes) -> FrameBlock:
    """The frames of one binary message, or ProtocolError (code ``bad-binary``) saying what is
    wrong with it."""
    if len(data) < HEADER.size:
        raise _malformed(f"the message has {len(data)} bytes, fewer than the 12-byte header")
    magic, version, count, channels, seq = HEADER.unpack_from(data)
    if magic != MAGIC or version != VERSION:
        raise _malformed(f"the message does not start with LVF and version {VERSION}")
    if not 0 < count <= MAX_BATCH or channels == 0:
        raise _malformed(f"a message holds 1 to {MAX_BATCH} frames of at least one value")
    expected = HEADER.size + VALUE.itemsize * count * channels
    if len(data) != expected:
        text = f"{count} frames of {channels} values take {expected} bytes; got {len(data)}"
        raise _malformed(text, seq)
    values = np.frombuffer(data, dtype=VALUE, offset=HEADER.size).reshape(count, channels)
    return FrameBlock(seq, values.astype(np.float64))


def _malformed(message: str, seq: int | None = None) -> ProtocolError:
    return ProtocolError("bad-binary", message, seq)


def take_frames(session: LiveSession, block: FrameBlock) -> list[Event]:
    """Events answering one binary message, as `LiveSession.handle` answers a JSON batch
    (`LiveSession.take_batch`'s rules; never raises for bad input)."""
    try:
        expected = session.aligner.n_channels if session.aligner is not None else None
        channels = block.values.shape[1]
        if expected is not None and channels != expected:  # every frame of it has that count
            text = f"frames from {block.seq} have {channels} values; the skeleton has {expected}"
            raise ProtocolError("value-count", text, block.seq)
        return session.take_batch(block.seq, block.values)
    except ProtocolError as error:
        session.errors += 1
        return [error_event(error)]
