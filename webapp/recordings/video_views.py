"""The uploaded phone video of a recording, served to the recording page's <video> element.

Same permission as the recording page (another clinic's recording, or another patient's, answers
404). Browsers seek in a video by asking for byte ranges (HTTP Range), so a single range is
answered with 206 and only its bytes; without a Range header the whole file streams.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from typing import IO

from django.contrib.auth.decorators import login_required
from django.http import (
    FileResponse,
    Http404,
    HttpRequest,
    HttpResponse,
    StreamingHttpResponse,
)
from django.http.response import HttpResponseBase

from analysis.sources.video import SUFFIXES as VIDEO_SUFFIXES
from webapp.accounts.permissions import get_recording_for_user
from webapp.audit import log
from webapp.recordings.models import Recording

CONTENT_TYPES = {".mp4": "video/mp4", ".mov": "video/quicktime", ".webm": "video/webm"}
CHUNK = 256 * 1024
RANGE = re.compile(r"^bytes=(\d*)-(\d*)$")


def video_suffix(recording: Recording) -> str | None:
    """The stored file's video ending (".mp4", ...), or None when it is not a video."""
    name = (recording.file.name or "").lower()
    return next((s for s in VIDEO_SUFFIXES if name.endswith(s)), None)


def parse_range(header: str, size: int) -> tuple[int, int] | None:
    """The first and last byte of a single ``bytes=`` range within ``size`` bytes; None for
    a header this view does not honour (several ranges, other units: the whole file is sent,
    which HTTP allows), ValueError for a range that lies outside the file (416)."""
    found = RANGE.match(header.strip())
    if found is None or found.group(1) == found.group(2) == "":
        return None
    first_text, last_text = found.groups()
    if first_text == "":  # "bytes=-500": the last 500 bytes
        first, last = max(0, size - int(last_text)), size - 1
    else:
        first = int(first_text)
        last = min(int(last_text), size - 1) if last_text else size - 1
    if first >= size or last < first:
        raise ValueError(f"bytes {header} lie outside a file of {size} bytes")
    return first, last


class ByteSlice:
    """Bytes ``first``..``last`` of an open file, in chunks. The response closes it (and the
    file) when done, even when the body is never read (a HEAD request, a dropped connection)."""

    def __init__(self, handle: IO[bytes], first: int, last: int) -> None:
        self.handle, self.first, self.last = handle, first, last

    def __iter__(self) -> Iterator[bytes]:
        self.handle.seek(self.first)
        left = self.last - self.first + 1
        while left > 0:
            chunk = self.handle.read(min(CHUNK, left))
            if not chunk:
                break
            left -= len(chunk)
            yield chunk

    def close(self) -> None:
        self.handle.close()


@login_required
def video(request: HttpRequest, pk) -> HttpResponseBase:
    recording = get_recording_for_user(request, pk, audit=False)
    suffix = video_suffix(recording)
    if suffix is None:
        raise Http404("This recording is not a video.")
    # One page view, one audit event: the video is part of the recording page.
    log.record_page_part(request, recording, patient_id=recording.patient_id)
    content_type = CONTENT_TYPES[suffix]
    try:
        size = recording.file.size
        handle = recording.file.storage.open(recording.file.name, "rb")
    except OSError as error:
        raise Http404("The video file is missing.") from error
    try:
        wanted = parse_range(request.headers.get("Range", ""), size)
    except ValueError:
        handle.close()
        response = HttpResponse(status=416)
        response["Content-Range"] = f"bytes */{size}"
        return response
    return ranged(handle, wanted, size, content_type)


def ranged(
    handle: IO[bytes], wanted: tuple[int, int] | None, size: int, content_type: str
) -> HttpResponseBase:
    if wanted is None:
        response: HttpResponseBase = FileResponse(handle, content_type=content_type)
        response["Content-Length"] = str(size)
    else:
        first, last = wanted
        response = StreamingHttpResponse(
            ByteSlice(handle, first, last), status=206, content_type=content_type
        )
        response["Content-Range"] = f"bytes {first}-{last}/{size}"
        response["Content-Length"] = str(last - first + 1)
    response["Accept-Ranges"] = "bytes"
    response["Cache-Control"] = "private, no-cache"
    return response
