"""History exports: CSV rows per recording (read back with the csv module and with pandas) and the
FHIR R4 Bundle, validated twice: with the `fhir.resources` models of the R4 line (R4B, 4.3.0;
the package's pure 4.0.1 models ended with its pydantic-1 releases) and with the strict FHIR
4.0.1 (R4) models of `fhirclient`; and the API's access rules (another clinic's patient: 404;
anonymous: 401)."""

from __future__ import annotations

import csv
import datetime
import io
import re
from pathlib import Path

import pandas as pd
import pytest
from django.urls import reverse
from django.utils import timezone
from fhir.resources.R4B.bundle import Bundle
from fhirclient.models.bundle import Bundle as R4Bundle
from fhirclient.models.observation import Observation as R4Observation
from fhirclient.models.patient import Patient as R4Patient
from rest_framework.test import APIClient

from analysis.clinical import ANGLE_NAMES
from analysis.clinical.labels import angle_label
from analysis.pipeline.results import AnalysisSummary, AngleRange, RepetitionResult
from tests.personas import make_exercise, make_recording
from webapp.accounts.tokens import issue_token
from webapp.audit.models import AuditEvent
from webapp.recordings.models import AnalysisRun, Recording, RunStatus

KNEE = AngleRange(2.5, 95.0)
TRUNK = AngleRange(-1.0, 28.25)


def summary(score: float, angles: dict[str, AngleRange], passed=(True, False, True)) -> dict:
    reps = tuple(
        RepetitionResult(start=10 * i, end=10 * i + 9, peak=10 * i + 5, score=score, passed=p)
        for i, p in enumerate(passed)
    )
    result = AnalysisSummary(
        frames=40, fps=30.0, landmarks=(), repetitions=reps, score=score, clinical_angles=angles
    )
    return result.to_json()


def analysed(patient, exercise, data: dict, days_ago: int) -> Recording:
    recording = make_recording(patient, exercise)
    AnalysisRun.objects.filter(recording=recording).update(status=RunStatus.SUCCEEDED, summary=data)
    when = timezone.now() - datetime.timedelta(days=days_ago)
    Recording.objects.filter(pk=recording.pk).update(uploaded_at=when)
    return recording


@pytest.fixture
def history(world):
    squat = make_exercise(world.clinic)
    old = summary(61.5, {})  # an older run: no clinical angles
    old.pop("clinical_angles")
    first = analysed(world.patient, squat, old, days_ago=9)
    angles = {"knee_flexion_left": KNEE, "trunk_flexion": TRUNK}
    second = analysed(world.patient, squat, summary(80.0, angles), days_ago=2)
    make_recording(world.patient, squat)  # not analysed yet: not exported
    return first, second


def api(user) -> APIClient:
    client = APIClient()
    _, key = issue_token(user, "practice system")
    client.credentials(HTTP_AUTHORIZATION=f"Token {key}")
    return client


def rows_of(response) -> list[dict[str, str]]:
    return list(csv.DictReader(io.StringIO(response.content.decode())))


def angle_column(name: str) -> str:
    return f"{angle_label(name).lower()} range (°)"


def test_history_csv_one_row_per_analysed_recording(world, history):
    url = reverse("api-patient-history-csv", kwargs={"pk": world.patient.pk})
    response = api(world.therapist).get(url)
    assert response.status_code == 200
    assert response["Content-Type"].startswith("text/csv")
    assert "attachment" in response["Content-Disposition"]
    header = next(csv.reader(io.StringIO(response.content.decode())))
    assert header[:4] == ["date (UTC)", "exercise", "score (/100)", "repetitions (count)"]
    assert header[4:7] == ["repetitions passed (count)", "pain (0-10)", "effort Borg CR10 (0-10)"]
    assert header[7:-1] == [angle_column(name) for name in ANGLE_NAMES]
    assert "left knee flexion range (°)" in header and header[-1] == "note"
    old, new = rows_of(response)
    assert old["exercise"] == new["exercise"] == "Deep squat"
    assert old["date (UTC)"] < new["date (UTC)"]
    counts = (old["repetitions (count)"], old["repetitions passed (count)"])
    assert (float(old["score (/100)"]), *counts) == (61.5, "3", "2")
    assert all(old[angle_column(name)] == "" for name in ANGLE_NAMES)  # older run: empty cells
    assert float(new["left knee flexion range (°)"]) == KNEE.range == 92.5
    assert float(new[angle_column("trunk_flexion")]) == TRUNK.range
    assert new["right knee flexion range (°)"] == ""
    assert AuditEvent.objects.filter(action="export", patient_id=world.patient.pk).exists()


DOCS = Path(__file__).resolve().parents[2] / "docs" / "sections" / "clinical.md"


def test_history_csv_opens_in_pandas_with_the_documented_columns(world, history):
    documented = re.search(r"oldest first: `([^`]+)`", DOCS.read_text().replace("\n  ", " "))
    assert documented is not None
    leading = [c.strip() for c in documented.group(1).split(",")]
    url = reverse("api-patient-history-csv", kwargs={"pk": world.patient.pk})
    frame = pd.read_csv(io.BytesIO(api(world.therapist).get(url).content))
    angles = [angle_column(name) for name in ANGLE_NAMES]
    assert list(frame.columns) == [*leading, *angles, "note"]
    assert len(frame) == 2  # the two analysed recordings; the one not analysed yet is left out
    assert pd.to_datetime(frame["date (UTC)"]).is_monotonic_increasing
    assert frame["score (/100)"].tolist() == [61.5, 80.0]
    assert frame["repetitions (count)"].tolist() == [3, 3]
    assert frame["repetitions passed (count)"].tolist() == [2, 2]
    assert frame["left knee flexion range (°)"].isna().tolist() == [True, False]
    assert frame["left knee flexion range (°)"].iloc[1] == KNEE.range
    assert frame[angles].iloc[0].isna().all()
    assert frame["note"].isna().all()  # both recordings show their exercise


def test_history_csv_for_a_patient_and_asking_for_csv(world, history):
    url = reverse("api-patient-history-csv", kwargs={"pk": world.patient.pk})
    client = APIClient()
    client.force_authenticate(world.patient_user)
    response = client.get(url, HTTP_ACCEPT="text/csv")
    assert response.status_code == 200 and len(rows_of(response)) == 2


def test_fhir_bundle_validates_and_holds_the_history(world, history):
    url = reverse("api-patient-fhir", kwargs={"pk": world.patient.pk})
    response = api(world.therapist).get(url)
    assert response.status_code == 200
    assert response["Content-Type"].startswith("application/fhir+json")
    data = response.json()
    bundle = Bundle.model_validate(data)  # raises on anything FHIR does not allow
    assert bundle.type == "collection"
    r4 = R4Bundle(data, strict=True)  # FHIR 4.0.1: raises on unknown or mistyped elements
    assert isinstance(r4.entry[0].resource, R4Patient)
    assert all(isinstance(e.resource, R4Observation) for e in r4.entry[1:])
    assert r4.entry[1].resource.valueQuantity.unit and r4.entry[1].resource.status == "final"
    resources = [e["resource"] for e in data["entry"]]
    patient = resources[0]
    assert patient["resourceType"] == "Patient" and patient["id"] == str(world.patient.pk)
    observations = resources[1:]
    assert all(o["subject"]["reference"] == f"urn:uuid:{world.patient.pk}" for o in observations)
    scores = [o for o in observations if o["code"]["coding"][0]["code"] == "session-score"]
    assert [o["valueQuantity"]["value"] for o in scores] == [61.5, 80.0]
    assert scores[0]["component"][0]["valueQuantity"]["value"] == 3
    knee = next(o for o in observations if o["code"]["coding"][0]["code"] == "knee_flexion_left")
    assert knee["valueRange"]["low"]["value"] == KNEE.min
    assert knee["valueRange"]["high"] == {
        "value": KNEE.max, "unit": "deg", "system": "http://unitsofmeasure.org", "code": "deg"
    }  # fmt: skip
    assert knee["component"][0]["valueQuantity"]["value"] == KNEE.range
    assert len(observations) == 2 + 2  # two scores, two angle ranges (the old run has none)
    assert len({o["id"] for o in observations}) == len(observations)
    again = api(world.therapist).get(url).json()
    assert [e["resource"]["id"] for e in again["entry"]] == [r["id"] for r in resources]


@pytest.mark.parametrize("name", ["api-patient-history-csv", "api-patient-fhir"])
def test_another_clinic_or_patient_gets_404_and_anonymous_401(world, history, name):
    own = reverse(name, kwargs={"pk": world.patient.pk})
    elsewhere = reverse(name, kwargs={"pk": world.outsider_patient.pk})
    assert api(world.outsider).get(own).status_code == 404
    assert api(world.therapist).get(elsewhere).status_code == 404
    client = APIClient()
    client.force_authenticate(world.other_patient_user)
    assert client.get(own).status_code == 404
    assert APIClient().get(own).status_code == 401


def test_empty_history(world):
    url = reverse("api-patient-fhir", kwargs={"pk": world.other_patient.pk})
    data = api(world.therapist).get(url).json()
    assert [e["resource"]["resourceType"] for e in data["entry"]] == ["Patient"]
    Bundle.model_validate(data)
    R4Bundle(data, strict=True)
    csv_url = reverse("api-patient-history-csv", kwargs={"pk": world.other_patient.pk})
    assert rows_of(api(world.therapist).get(csv_url)) == []
