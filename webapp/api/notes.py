"""`GET|POST /api/v1/recordings/{id}/notes/`: a recording's clinical notes, oldest first.

Everyone who may see the recording reads its notes (its patient too); the clinic's therapists
and admins write them. Another clinic's recording answers 404.
"""

from __future__ import annotations

from drf_spectacular.utils import extend_schema
from rest_framework import serializers, status
from rest_framework.exceptions import PermissionDenied
from rest_framework.request import Request
from rest_framework.response import Response
from rest_framework.views import APIView

from webapp.accounts.permissions import get_recording_for_user
from webapp.api.serializers import UTCDateTimeField
from webapp.recordings.models import RecordingNote
from webapp.recordings.notes import MAX_NOTE_LENGTH, add_note, author_name, notes_of


class NoteSerializer(serializers.Serializer):
    id = serializers.UUIDField()
    text = serializers.CharField()
    author = serializers.CharField(help_text="the author's name")
    created_at = UTCDateTimeField()


class NotesSerializer(serializers.Serializer):
    recording = serializers.UUIDField()
    notes = NoteSerializer(many=True)


class NoteInputSerializer(serializers.Serializer):
    text = serializers.CharField(max_length=MAX_NOTE_LENGTH, trim_whitespace=True)


def note_body(note: RecordingNote) -> dict:
    row = {
        "id": note.pk,
        "text": note.text,
        "author": author_name(note.author),
        "created_at": note.created_at,
    }
    return NoteSerializer(row).data


class RecordingNotes(APIView):
    """A recording's clinical notes; the clinic's staff add new ones."""

    @extend_schema(responses={200: NotesSerializer})
    def get(self, request: Request, pk) -> Response:
        recording = get_recording_for_user(request, pk)
        notes = [note_body(note) for note in notes_of(recording)]
        return Response({"recording": str(recording.pk), "notes": notes})

    @extend_schema(request=NoteInputSerializer, responses={201: NoteSerializer})
    def post(self, request: Request, pk) -> Response:
        recording = get_recording_for_user(request, pk, audit=False)  # the note is the event
        if not request.user.is_staff_member:
            raise PermissionDenied("Only the clinic's therapists write clinical notes.")
        data = NoteInputSerializer(data=request.data)
        data.is_valid(raise_exception=True)
        note = add_note(request, recording, data.validated_data["text"])
        return Response(note_body(note), status=status.HTTP_201_CREATED)
