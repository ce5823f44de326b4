"""The compare page (`/patients/{id}/compare/?a=…&b=…`): scope, both recordings' figures side by
side, the angle difference b − a, the different-exercise message, the default choice, and the
"compare with the first session" link on the recording page and the patient page."""

from __future__ import annotations

import datetime
import re

import pytest
from django.urls import reverse
from django.utils import timezone

from analysis.clinical import ANGLE_NAMES
from analysis.pipeline.results import AnalysisSummary
from tests.personas import make_exercise, make_recording
from webapp.patients.compare import angle_comparison, comparison
from webapp.recordings.models import AnalysisRun, Recording, RepetitionLabel, RunStatus


def summary(scores, passed, angles, corrections=()) -> dict:
    """A succeeded run's stored result: one repetition per score, clinical angles as
    {name: (min, max)}, and the corrections' sentences."""
    return {
        "frames": 100, "fps": 25.0, "landmarks": [],
        "score": sum(scores) / len(scores) if scores else 0.0, "pass_threshold": 70.0,
        "repetitions": [
            {"start": 10 * i, "end": 10 * i + 9, "peak": 10 * i + 5, "score": s, "passed": p}
            for i, (s, p) in enumerate(zip(scores, passed, strict=True))
        ],
        "clinical_angles": {
            name: {"min": lo, "max": hi, "range": hi - lo} for name, (lo, hi) in angles.items()
        },
        "advice": {"corrections": [{"text": text} for text in corrections], "went_well": []},
    }  # fmt: skip


def analysed(patient, exercise, data: dict, days_ago: int) -> Recording:
    recording = make_recording(patient, exercise)
    AnalysisRun.objects.filter(recording=recording).update(status=RunStatus.SUCCEEDED, summary=data)
    when = timezone.now() - datetime.timedelta(days=days_ago)
    Recording.objects.filter(pk=recording.pk).update(uploaded_at=when)
    return Recording.objects.get(pk=recording.pk)


FIRST = summary(
    [55.0, 61.0],
    [False, False],
    {"knee_flexion_left": (5.0, 85.0), "trunk_flexion": (0.0, 30.0)},
    ["Bend your left knee more."],
)
LATEST = summary(
    [82.0, 90.0, 77.0],
    [True, True, True],
    {"knee_flexion_left": (2.0, 95.0), "trunk_flexion": (0.0, 21.0), "hip_flexion_left": (0, 60)},
    ["Keep your back straighter."],
)


@pytest.fixture
def squat(world):
    exercise = make_exercise(world.clinic)
    exercise.involved_joints = ["KneeLeft", "KneeRight"]
    exercise.save()
    return exercise


@pytest.fixture
def sessions(world, squat):
    """Ann's squats: the first (20 days ago), one in between, the latest (1 day ago)."""
    first = analysed(world.patient, squat, FIRST, days_ago=20)
    middle = analysed(world.patient, squat, summary([70.0], [True], {}), days_ago=10)
    latest = analysed(world.patient, squat, LATEST, days_ago=1)
    return first, middle, latest


def compare_url(patient, a=None, b=None) -> str:
    url = reverse("patients:compare", kwargs={"pk": patient.pk})
    query = "&".join(f"{k}={v.pk}" for k, v in (("a", a), ("b", b)) if v is not None)
    return f"{url}?{query}" if query else url


def get(client, user, url: str):
    client.force_login(user)
    return client.get(url)


def section(html: str, element_id: str) -> str:
    start = html.index(f'id="{element_id}"')
    return html[start : html.index("</section>", start)]


def test_outsiders_and_other_patients_get_404(client, world, sessions):
    first, _, latest = sessions
    url = compare_url(world.patient, first, latest)
    assert get(client, world.outsider, url).status_code == 404  # another clinic
    assert get(client, world.other_patient_user, url).status_code == 404  # another patient
    assert get(client, world.patient_user, url).status_code == 200  # the patient themselves
    assert get(client, world.colleague, url).status_code == 200  # staff of the same clinic


def test_a_recording_of_another_patient_or_no_recording_is_404(client, world, squat, sessions):
    first, _, latest = sessions
    bob = analysed(world.other_patient, squat, FIRST, days_ago=3)
    page = reverse("patients:compare", kwargs={"pk": world.patient.pk})
    for query in (f"a={bob.pk}&b={latest.pk}", f"a={first.pk}&b={bob.pk}", "a=nonsense&b=1"):
        assert get(client, world.therapist, f"{page}?{query}").status_code == 404
    # Bob's recording through Bob's own compare page is fine.
    assert (
        get(client, world.therapist, compare_url(world.other_patient, bob, bob)).status_code == 200
    )


def test_both_recordings_figures_are_side_by_side(client, world, sessions):
    first, _, latest = sessions
    html = get(client, world.therapist, compare_url(world.patient, first, latest)).content.decode()
    side_a, side_b = section(html, "compare-side-a"), section(html, "compare-side-b")
    assert re.search(r"Score <strong[^>]*>58</strong> / 100", side_a)  # (55 + 61) / 2
    assert "2 repetitions done, 0 passed" in side_a
    assert "Bend your left knee more." in side_a
    assert re.search(r"Score <strong[^>]*>83</strong> / 100", side_b)  # (82 + 90 + 77) / 3
    assert "3 repetitions done, 3 passed" in side_b
    assert "Keep your back straighter." in side_b
    reps = section(html, "compare-repetitions")
    assert re.search(r"#1</td>\s*<td>55</td>.*?not passed.*?<td>82</td>", reps, re.S)
    assert re.search(r"#3</td>\s*<td class=\"muted\" colspan=\"2\">–</td>\s*<td>77</td>", reps)
    assert "different exercises" not in html
    assert html.count("<canvas") == 2
    assert not any(name in html for name in ANGLE_NAMES)  # plain labels only


def test_angle_difference_is_b_minus_a_in_degrees(client, world, sessions):
    first, _, latest = sessions
    html = get(client, world.therapist, compare_url(world.patient, first, latest)).content.decode()
    angles = section(html, "compare-angles")
    knee = re.search(r"<td>Left knee flexion</td>(.*?)</tr>", angles, re.S).group(1)
    assert "<strong>80°</strong>" in knee and "<strong>93°</strong>" in knee
    assert "<strong>+13°</strong>" in knee  # 93 − 80
    trunk = re.search(r"<td>Trunk flexion</td>(.*?)</tr>", angles, re.S).group(1)
    assert "<strong>-9°</strong>" in trunk  # 21 − 30: less trunk bending in B
    hip = re.search(r"<td>Left hip flexion</td>(.*?)</tr>", angles, re.S).group(1)
    assert "not measured" in hip  # only B measured it: no difference
    assert hip.rstrip().endswith('<td class="angle-difference">–</td>')


def test_angle_comparison_on_constructed_results():
    a = AnalysisSummary.from_json(FIRST)
    b = AnalysisSummary.from_json(LATEST)
    rows = {row["name"]: row for g in angle_comparison(a, b, ["KneeLeft"]) for row in g["rows"]}
    assert rows["knee_flexion_left"]["difference"] == pytest.approx(13.0)
    assert rows["trunk_flexion"]["difference"] == pytest.approx(-9.0)
    assert rows["hip_flexion_left"]["a"] is None and rows["hip_flexion_left"]["difference"] is None
    swapped = {r["name"]: r for g in angle_comparison(b, a, []) for r in g["rows"]}
    assert swapped["knee_flexion_left"]["difference"] == pytest.approx(-13.0)


def test_therapist_verdicts_count_in_passed(world, sessions):
    first, _, latest = sessions
    run = first.latest_succeeded_run()
    RepetitionLabel.objects.create(run=run, index=1, passed=True, author=world.therapist)
    found = comparison(first, latest)
    assert found["a"]["passed"] == 1
    assert [rep["passed"] for rep in found["a"]["repetitions"]] == [False, True]
    assert found["a"]["therapist_changes"] == ["Repetition 2 marked passed by the therapist."]


def test_different_exercises_are_said_plainly(client, world, squat, sessions):
    _, _, latest = sessions
    arm = make_exercise(world.clinic, name="Shoulder abduction")
    raise_arm = analysed(world.patient, arm, FIRST, days_ago=2)
    html = get(client, world.therapist, compare_url(world.patient, raise_arm, latest)).content
    html = html.decode()
    message = html[html.index('id="different-exercises"') :]
    assert "different exercises (Shoulder abduction and Deep squat)" in message
    assert "<strong>+13°</strong>" in section(html, "compare-angles")  # still compared


def test_without_a_and_b_the_form_picks_newest_and_first_of_its_exercise(client, world, sessions):
    first, _, latest = sessions
    arm = make_exercise(world.clinic, name="Shoulder abduction")
    analysed(world.patient, arm, FIRST, days_ago=30)  # older, but another exercise
    html = get(client, world.therapist, compare_url(world.patient)).content.decode()
    select_a = re.search(r'<select name="a".*?</select>', html, re.S).group(0)
    select_b = re.search(r'<select name="b".*?</select>', html, re.S).group(0)
    assert re.search(rf'value="{first.pk}" selected', select_a)
    assert re.search(rf'value="{latest.pk}" selected', select_b)
    assert select_a.count("<option") == 4  # every analysed recording, either exercise
    assert "compare-summary" not in html  # nothing compared until both are chosen


def test_recording_page_links_to_compare_with_first_session(client, world, sessions):
    first, middle, latest = sessions
    html = get(client, world.therapist, reverse("recordings:detail", kwargs={"pk": latest.pk}))
    link = re.search(r'id="compare-first"><a class="button" href="([^"]+)"', html.content.decode())
    assert link.group(1) == compare_url(world.patient, first, latest).replace("&", "&amp;")
    page = get(client, world.therapist, link.group(1).replace("&amp;", "&"))
    assert page.status_code == 200 and "compare-summary" in page.content.decode()
    middle_page = get(
        client, world.therapist, reverse("recordings:detail", kwargs={"pk": middle.pk})
    )
    expected = compare_url(world.patient, first, middle).replace("&", "&amp;")
    assert f'href="{expected}"' in middle_page.content.decode()
    first_page = get(client, world.therapist, reverse("recordings:detail", kwargs={"pk": first.pk}))
    assert 'id="compare-first"' not in first_page.content.decode()  # it is the first one


def test_patient_page_has_a_compare_link(client, world, sessions):
    html = get(client, world.therapist, reverse("patients:detail", kwargs={"pk": world.patient.pk}))
    assert f'href="{compare_url(world.patient)}"' in html.content.decode()
