"""Reading an uploaded recording's file and recording its basic facts."""

from __future__ import annotations

from typing import Any

from analysis.sources import read_recording
from webapp.recordings.models import Recording
from webapp.recordings.storage import read_verified


def inspect_recording(recording_id: str) -> dict[str, Any]:
    recording = Recording.all_objects.get(pk=recording_id)
    motion = read_recording(recording.file.name, read_verified(recording)).motion
    facts = {
        "n_frames": int(motion.frames.shape[0]),
        "n_joints": len(motion.skeleton.names),
        "fps": 1.0 / motion.frame_time,
        "duration_s": motion.frames.shape[0] * motion.frame_time,
    }
    Recording.objects.filter(pk=recording.pk).update(**facts)
    return facts
