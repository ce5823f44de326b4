"""Clinical notes per recording (issue 23, item 4): `GET|POST /api/v1/recordings/{id}/notes/`
(staff write, the recording's patient reads, another clinic gets 404, writes audited), the
recording page's "Clinical notes" section and form, and the note in the recording's reports."""

from __future__ import annotations

import pytest
from django.urls import reverse
from rest_framework.test import APIClient

from tests.personas import make_exercise, make_recording
from tests.webapp.test_clinical_pages import analysed, pdf_text, section, squat_angles, summary
from webapp.audit.models import AuditEvent
from webapp.recordings.models import RecordingNote
from webapp.reports.content import recording_content
from webapp.reports.pdf import recording_pdf
from webapp.reports.services import recording_report_name

NOTE = "Knee drifts inwards on the way down; cue to push the knees out."


def url(recording) -> str:
    return f"/api/v1/recordings/{recording.pk}/notes/"


def as_user(user) -> APIClient:
    api = APIClient()
    api.force_authenticate(user)
    return api


@pytest.fixture
def recording(world):
    return make_recording(world.patient, make_exercise(world.clinic))


def test_therapist_writes_a_note_and_everyone_allowed_reads_it(world, recording):
    answer = as_user(world.therapist).post(url(recording), {"text": f"  {NOTE}\n"}, format="json")
    assert answer.status_code == 201, answer.content
    body = answer.json()
    assert set(body) == {"id", "text", "author", "created_at"}
    assert body["text"] == NOTE and body["author"] == "therapist"
    assert body["created_at"].endswith("Z")
    stored = RecordingNote.objects.get(pk=body["id"])
    assert (stored.recording, stored.author, stored.text) == (recording, world.therapist, NOTE)
    for reader in (world.colleague, world.clinic_admin, world.patient_user):
        listed = as_user(reader).get(url(recording))
        assert listed.status_code == 200
        assert [n["text"] for n in listed.json()["notes"]] == [NOTE], reader.username


def test_notes_are_listed_oldest_first(world, recording):
    for text in ("First visit.", "Second visit."):
        as_user(world.therapist).post(url(recording), {"text": text}, format="json")
    notes = as_user(world.therapist).get(url(recording)).json()["notes"]
    assert [n["text"] for n in notes] == ["First visit.", "Second visit."]


def test_a_patient_reads_but_does_not_write(world, recording):
    answer = as_user(world.patient_user).post(url(recording), {"text": NOTE}, format="json")
    assert answer.status_code == 403
    assert not RecordingNote.objects.exists()


def test_other_patients_and_other_clinics_get_404(world, recording):
    for stranger in (world.outsider, world.other_patient_user):
        assert as_user(stranger).get(url(recording)).status_code == 404
        answer = as_user(stranger).post(url(recording), {"text": NOTE}, format="json")
        assert answer.status_code == 404
    assert not RecordingNote.objects.exists()


@pytest.mark.parametrize("body", [{}, {"text": "   "}, {"text": "x" * 4001}])
def test_an_empty_or_overlong_note_is_400_naming_the_field(world, recording, body):
    answer = as_user(world.therapist).post(url(recording), body, format="json")
    assert answer.status_code == 400
    assert "text" in answer.json()
    assert not RecordingNote.objects.exists()


def test_writing_a_note_is_audited(world, recording):
    answer = as_user(world.therapist).post(url(recording), {"text": NOTE}, format="json")
    event = AuditEvent.objects.get(action="create", object_type="RecordingNote")
    assert event.object_id == answer.json()["id"]
    assert (event.user, event.patient_id, event.clinic) == (
        world.therapist,
        world.patient.pk,
        world.clinic,
    )


def test_recording_page_lists_notes_and_offers_the_form_to_staff(client, world, recording):
    client.force_login(world.therapist)
    page_url = reverse("recordings:detail", kwargs={"pk": recording.pk})
    answer = client.post(
        reverse("recordings:add-note", kwargs={"pk": recording.pk}), {"text": NOTE}
    )
    assert answer.status_code == 302 and answer["Location"].endswith("#clinical-notes")
    notes = section(client.get(page_url).content.decode(), "clinical-notes")
    assert "Clinical notes" in notes and NOTE in notes
    assert "therapist" in notes  # the author
    assert 'id="add-note"' in notes
    client.force_login(world.patient_user)
    notes = section(client.get(page_url).content.decode(), "clinical-notes")
    assert NOTE in notes and 'id="add-note"' not in notes


def test_a_patient_cannot_post_the_note_form(client, world, recording):
    client.force_login(world.patient_user)
    answer = client.post(
        reverse("recordings:add-note", kwargs={"pk": recording.pk}), {"text": NOTE}
    )
    assert answer.status_code == 403
    assert not RecordingNote.objects.exists()


def test_the_page_form_refuses_an_empty_note(client, world, recording):
    client.force_login(world.therapist)
    client.post(reverse("recordings:add-note", kwargs={"pk": recording.pk}), {"text": "  "})
    assert not RecordingNote.objects.exists()


def test_the_recording_pdf_and_printable_report_carry_the_note(client, world):
    recording = analysed(world.patient, make_exercise(world.clinic), summary(80.0, squat_angles()))
    before = recording_report_name(recording)
    as_user(world.therapist).post(url(recording), {"text": NOTE}, format="json")
    text = pdf_text(recording_pdf(recording_content(recording)))
    assert "Clinical notes" in text
    assert "cue to push the knees out." in text and "therapist" in text
    assert recording_report_name(recording) != before  # a stored PDF without the note is not reused
    client.force_login(world.therapist)
    printed = client.get(reverse("reports:recording-print", kwargs={"pk": recording.pk}))
    assert NOTE in printed.content.decode()


def test_a_recording_without_analysis_still_prints_its_notes(world, recording):
    as_user(world.therapist).post(url(recording), {"text": NOTE}, format="json")
    text = pdf_text(recording_pdf(recording_content(recording)))
    assert "no analysis result yet" in text and "cue to push the knees out." in text
