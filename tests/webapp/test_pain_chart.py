"""Pain over time (issue 23, item 4): the pain score (0–10) of each session as a chart on the
patient page, and "Pain rising" on the therapist's attention list, with its rule in words."""

from __future__ import annotations

import datetime

import pytest
from django.urls import reverse
from django.utils import timezone

from tests.personas import make_exercise, make_recording
from webapp.dashboard.attention import pain_trend, patients_needing_attention
from webapp.dashboard.precompute import refresh_clinic
from webapp.patients.pain import pain_chart, pain_series
from webapp.recordings.models import Recording


def scored(patient, exercise, pain: int, days_ago: int, hour: int = 10) -> Recording:
    recording = make_recording(patient, exercise)
    day = timezone.localdate() - datetime.timedelta(days=days_ago)
    when = timezone.make_aware(datetime.datetime.combine(day, datetime.time(hour)))
    Recording.objects.filter(pk=recording.pk).update(uploaded_at=when, pain_score=pain)
    return recording


@pytest.fixture
def squat(world):
    return make_exercise(world.clinic)


def pain_reasons(world) -> list[str]:
    found = patients_needing_attention(world.clinic.pk)
    return [r.text for a in found if a.patient_id == world.patient.pk for r in a.reasons]


def test_pain_series_one_point_per_session_oldest_first(world, squat):
    for pain, days_ago, hour in ((2, 6, 9), (3, 3, 9), (5, 3, 17), (4, 1, 9)):
        scored(world.patient, squat, pain, days_ago, hour)
    make_recording(world.patient, squat)  # no pain given: no point
    assert [s["score"] for s in pain_series(world.patient)] == [2, 3, 5, 4]
    chart = pain_chart(world.patient)
    xs = [p["x"] for p in chart["points"]]
    assert xs == sorted(xs) and len(set(xs)) == 4  # same-day sessions side by side
    ys = {p["score"]: p["y"] for p in chart["points"]}
    assert ys[5] < ys[4] < ys[3] < ys[2]  # more pain higher up (SVG y grows downwards)
    assert chart["top"] <= min(ys.values()) and max(ys.values()) <= chart["bottom"]
    assert [t["text"] for t in chart["y_ticks"]] == ["0", "2", "4", "6", "8", "10"]
    assert len(chart["x_ticks"]) <= 9


def test_patient_page_shows_the_pain_chart_with_units(client, world, squat):
    scored(world.patient, squat, 3, 2)
    scored(world.patient, squat, 6, 1)
    client.force_login(world.therapist)
    html = client.get(reverse("patients:detail", kwargs={"pk": world.patient.pk})).content.decode()
    section = html[html.index('id="pain-over-time"') :]
    assert "Pain over time (0–10" in section and "pain (0–10)" in section
    assert section.count('class="pain-point"') == 2
    assert "pain 6 (0–10)" in section


def test_patient_page_without_pain_says_so(client, world, squat):
    client.force_login(world.therapist)
    html = client.get(reverse("patients:detail", kwargs={"pk": world.patient.pk})).content.decode()
    assert "No pain score reported yet." in html


def test_rising_pain_is_on_the_attention_list_in_words(world, squat):
    for pain, days_ago in ((3, 5), (4, 3), (5, 1)):  # below the high-pain mark, but rising
        scored(world.patient, squat, pain, days_ago)
    assert "Pain rising: 3 → 5 (0–10) over the last 3 sessions" in pain_reasons(world)


def test_the_home_page_attention_list_says_pain_is_rising(client, world, squat):
    for pain, days_ago in ((2, 5), (3, 3), (4, 1)):
        scored(world.patient, squat, pain, days_ago)
    refresh_clinic(world.clinic.pk)  # the home page reads the stored list
    client.force_login(world.therapist)
    html = client.get("/").content.decode()
    section = html[html.index('id="attention"') :]
    assert world.patient.display_name in section
    assert "Pain rising: 2 → 4 (0–10) over the last 3 sessions" in section


def test_flat_or_falling_pain_is_not_rising(world, squat):
    for pain, days_ago in ((4, 7), (4, 5), (4, 3), (5, 1)):
        scored(world.patient, squat, pain, days_ago)
    assert not any(text.startswith("Pain rising") for text in pain_reasons(world))


def test_only_the_last_three_sessions_count(world, squat):
    for pain, days_ago in ((1, 9), (6, 5), (4, 3), (5, 1)):  # 1 → 5 overall, but 6 → 4 → 5 last
        scored(world.patient, squat, pain, days_ago)
    assert not any(text.startswith("Pain rising") for text in pain_reasons(world))


def test_old_rising_pain_is_not_news(world, squat):
    for pain, days_ago in ((2, 40), (4, 35), (5, 30)):
        scored(world.patient, squat, pain, days_ago)
    assert not any(text.startswith("Pain rising") for text in pain_reasons(world))


@pytest.mark.parametrize(
    ("scores", "rising"),
    [([3, 4, 5], True), ([3, 3, 5], True), ([3, 4, 4], False), ([5, 7, 6], False), ([3, 6], False)],
)
def test_the_rule(scores, rising):
    assert (pain_trend(scores) is not None) is rising
