"""Clinical notes on a recording: therapists and clinic admins write them; everyone who may see
the recording (its patient too) reads them on its page, in its PDF report and in the API.

Writing a note is audited like every write of patient data (`webapp.audit.log`).
"""

from __future__ import annotations

from typing import Any

from django import forms
from django.contrib import messages
from django.contrib.auth.decorators import login_required
from django.http import HttpRequest, HttpResponse
from django.shortcuts import redirect
from django.urls import reverse
from django.views.decorators.http import require_POST

from webapp.accounts.permissions import get_recording_for_user, require_staff
from webapp.audit import log
from webapp.recordings.models import Recording, RecordingNote

MAX_NOTE_LENGTH = 4000


class NoteForm(forms.Form):
    text = forms.CharField(
        label="New note",
        max_length=MAX_NOTE_LENGTH,
        widget=forms.Textarea(attrs={"rows": 3}),
        strip=True,
    )


def author_name(user) -> str:
    """The name a note is signed with (its author's full name, else username)."""
    if user is None:
        return "a former member of staff"
    return user.get_full_name() or user.get_username()


def add_note(request: HttpRequest, recording: Recording, text: str) -> RecordingNote:
    note = RecordingNote.objects.create(recording=recording, author=request.user, text=text)
    log.record(request, "create", note, patient_id=recording.patient_id)
    return note


def notes_of(recording: Recording) -> list[RecordingNote]:
    """The recording's notes, oldest first, with their authors (one query)."""
    return list(recording.notes.select_related("author"))


def note_lines(recording: Recording) -> list[dict[str, Any]]:
    """The notes as reports print them: {"text", "author", "date"}."""
    return [
        {
            "text": note.text,
            "author": author_name(note.author),
            "date": f"{note.created_at:%d %b %Y %H:%M}",
        }
        for note in notes_of(recording)
    ]


@login_required
@require_staff
@require_POST
def add(request: HttpRequest, pk) -> HttpResponse:
    """The recording page's note form (therapists and clinic admins)."""
    recording = get_recording_for_user(request, pk, audit=False)  # the note is the event
    form = NoteForm(request.POST)
    if form.is_valid():
        add_note(request, recording, form.cleaned_data["text"])
        messages.success(request, "Note added.")
    else:  # nothing written: the visit is a read of the recording
        log.record(request, "read", recording, patient_id=recording.patient_id)
        messages.error(
            request, "The note was not saved: write some text (4000 characters at most)."
        )
    return redirect(reverse("recordings:detail", kwargs={"pk": recording.pk}) + "#clinical-notes")
