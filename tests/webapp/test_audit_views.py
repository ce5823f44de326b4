"""The audit log reads right: one event per view of a recording's page (its playback fetches
folded in), naming what was seen in words and keeping the full path; the clinic admin's page
filters by date and downloads the filtered events as CSV."""

from __future__ import annotations

import csv
import datetime
import io

import pytest
from django.test import Client
from django.urls import reverse
from django.utils import timezone

from tests.personas import make_exercise, make_recording
from webapp.accounts.models import Role, User
from webapp.audit import log
from webapp.audit.models import AuditEvent

UTC = datetime.UTC


@pytest.fixture
def recording(world):
    return make_recording(world.patient, make_exercise(world.clinic))


def signed_in(user) -> Client:
    client = Client()
    client.force_login(user)
    return client


def view_recording_page(client: Client, recording) -> None:
    """What a browser does: the page, then the playback data its script fetches."""
    assert client.get(reverse("recordings:detail", kwargs={"pk": recording.pk})).status_code == 200
    client.get(reverse("reports:playback", kwargs={"pk": recording.pk}))
    client.get(reverse("reports:playback-bin", kwargs={"pk": recording.pk}))


def reads_of(recording) -> list[AuditEvent]:
    return list(AuditEvent.objects.filter(action="read", object_id=str(recording.pk)))


def test_one_event_per_view_of_a_recording_page(world, recording):
    view_recording_page(signed_in(world.therapist), recording)
    (event,) = reads_of(recording)
    assert event.path == f"/recordings/{recording.pk}/"  # whole, with the recording's id
    uploaded = timezone.localtime(recording.uploaded_at)
    day = f"{uploaded.day} {uploaded:%b %Y}"
    assert event.description == f"recording of Ann Example — Deep squat, {day}"
    assert event.what == event.description


def test_each_page_view_is_an_event_and_each_viewer_their_own(world, recording):
    therapist = signed_in(world.therapist)
    view_recording_page(therapist, recording)
    view_recording_page(therapist, recording)  # looked at it again: a second view
    view_recording_page(signed_in(world.patient_user), recording)
    events = reads_of(recording)
    assert len(events) == 3
    assert sorted(e.username for e in events) == ["patient", "therapist", "therapist"]


def test_playback_fetched_on_its_own_is_an_event(world, recording, monkeypatch):
    client = signed_in(world.therapist)
    client.get(reverse("reports:playback", kwargs={"pk": recording.pk}))
    playback = reverse("reports:playback", kwargs={"pk": recording.pk})
    assert [e.path for e in reads_of(recording)] == [playback]
    monkeypatch.setattr(log, "FOLD_WINDOW", datetime.timedelta(0))  # the earlier read is old
    client.get(reverse("reports:playback-bin", kwargs={"pk": recording.pk}))
    assert len(reads_of(recording)) == 2


def test_the_words_stay_as_seen_after_a_rename(world, recording):
    view_recording_page(signed_in(world.therapist), recording)
    world.patient.display_name = "Ann Renamed"
    world.patient.save()
    (event,) = reads_of(recording)
    assert "Ann Example" in event.what and "Renamed" not in event.what


def event_on(monkeypatch, day: datetime.datetime, user, patient) -> None:
    """A read of the patient's page at `day` (the event's time is set by the clock)."""
    with monkeypatch.context() as clock:
        clock.setattr(timezone, "now", lambda: day)
        signed_in(user).get(reverse("patients:detail", kwargs={"pk": patient.pk}))


@pytest.fixture
def three_days(world, monkeypatch):
    march = datetime.datetime(2026, 3, 1, tzinfo=UTC)
    event_on(monkeypatch, march.replace(hour=23, minute=59), world.therapist, world.patient)
    event_on(monkeypatch, march.replace(day=2, hour=8), world.colleague, world.patient)
    event_on(monkeypatch, march.replace(day=4), world.therapist, world.other_patient)
    assert AuditEvent.objects.count() == 3


def test_the_page_filters_by_utc_days_both_included(world, three_days):
    client = signed_in(world.clinic_admin)
    page = client.get(reverse("audit:events"), {"since": "2026-03-02", "until": "2026-03-04"})
    rows = page.context["rows"]
    seen = [(e.username, name) for e, name in rows]
    assert seen == [("therapist", "Bob Example"), ("colleague", "Ann Example")]
    html = page.content.decode()
    assert "patient record of Bob Example" in html and "Download CSV" in html
    only_first = client.get(reverse("audit:events"), {"until": "2026-03-01"})
    assert [e.at.day for e, _ in only_first.context["rows"]] == [1]


def test_a_reversed_or_mistyped_date_shows_why_and_no_events(world, three_days):
    client = signed_in(world.clinic_admin)
    page = client.get(reverse("audit:events"), {"since": "2026-03-04", "until": "2026-03-01"})
    assert page.context["rows"] == []
    assert "The first day comes after the last one." in page.content.decode()
    export = client.get(reverse("audit:export"), {"since": "March"})
    assert export.status_code == 400 and b"date" in export.content


def csv_rows(response) -> list[dict[str, str]]:
    text = b"".join(response.streaming_content).decode()
    return list(csv.DictReader(io.StringIO(text)))


def test_the_csv_holds_the_filtered_events_with_full_paths(world, three_days, recording):
    view_recording_page(signed_in(world.therapist), recording)  # today: after the filter's days
    client = signed_in(world.clinic_admin)
    march = {"since": "2026-03-02", "until": "2026-03-03", "patient": world.patient.pk}
    page = client.get(reverse("audit:events"), march)
    link = page.content.decode().split('id="audit-csv" href="')[1].split('"')[0]
    assert link.startswith(reverse("audit:export") + "?") and "until=2026-03-03" in link
    response = client.get(link.replace("&amp;", "&"))
    assert response.status_code == 200 and response["Content-Type"].startswith("text/csv")
    assert "attachment" in response["Content-Disposition"]
    (row,) = csv_rows(response)
    assert row["when (UTC)"] == "2026-03-02 08:00:00"
    assert (row["who"], row["action"], row["patient"]) == ("colleague", "Read", "Ann Example")
    assert row["what"] == "patient record of Ann Example"
    assert row["path"] == f"/patients/{world.patient.pk}/"


def test_the_csv_of_every_event_names_the_recording_seen(world, recording):
    view_recording_page(signed_in(world.therapist), recording)
    rows = csv_rows(signed_in(world.clinic_admin).get(reverse("audit:export")))
    recording_rows = [r for r in rows if str(recording.pk) in r["path"]]
    assert len(recording_rows) == 1
    assert recording_rows[0]["what"].startswith("recording of Ann Example — Deep squat, ")


def test_only_the_clinic_admin_downloads_the_log_of_their_clinic(world, three_days):
    url = reverse("audit:export")
    assert signed_in(world.therapist).get(url).status_code == 403
    assert signed_in(world.patient_user).get(url).status_code == 403
    assert Client().get(url).status_code == 302  # to the login page
    assert len(csv_rows(signed_in(world.clinic_admin).get(url))) == 3
    elsewhere = User.objects.create_user(
        "south-admin",
        password="x-long-password-9",
        clinic=world.other_clinic,
        role=Role.CLINIC_ADMIN,
    )
    assert csv_rows(signed_in(elsewhere).get(url)) == []
