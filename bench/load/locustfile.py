"""Load on the clinic web app: therapists browsing and recordings uploaded through the API.

Driven by bench/load/run_load.py (which starts gunicorn, two Celery workers, PostgreSQL data and
Redis, and writes the plan this file reads); loopback only. Two kinds of simulated users:

- `Therapist` (50): with a session made by setup_load.py, browses the dashboard, the patient
  list, patients' pages, progress (JSON and API), history (API) and recording pages, 1–3 s apart.
- `Uploader` (20): with an API token from setup_load.py, uploads a real UI-PRMD BVH for its
  own patient, polls the recording every second until the analysis has finished, and starts
  again. The time from the upload to the poll that sees the result is reported as
  `RESULT upload-to-result`.

Pages are named by route (ids replaced by {id}) so their figures aggregate.
"""

from __future__ import annotations

import itertools
import json
import os
import random
import struct
import time
from pathlib import Path

from locust import HttpUser, between, events, task

PLAN = json.loads(Path(os.environ.get("LOAD_PLAN", "var/load/plan.json")).read_text())
POLL_SECONDS = 1.0
UPLOAD_STAMPS = itertools.count(int(time.time()))
RESULT_TIMEOUT_S = 600.0


def unique_copy(path: str) -> bytes:
    """The gzip file with a new header timestamp: the same motion, another checksum, so that the
    app's duplicate-upload check (same file, same patient: 400) does not refuse repeat uploads."""
    content = bytearray(Path(path).read_bytes())
    content[4:8] = struct.pack("<I", next(UPLOAD_STAMPS) & 0xFFFFFFFF)
    return bytes(content)


class Therapist(HttpUser):
    fixed_count = int(os.environ.get("LOAD_THERAPISTS", "50"))
    wait_time = between(1, 3)

    def on_start(self) -> None:
        # Signed in by setup_load.py (see there why); the cookie is the browser's session.
        host = self.host.split("://", 1)[1].split(":")[0]
        self.client.cookies.set("sessionid", PLAN["sessions"].pop(), domain=host, path="/")

    def patient(self) -> str:
        return random.choice(PLAN["patients"])

    def recording(self) -> str:
        return random.choice(PLAN["recordings"])

    @task(3)
    def dashboard(self) -> None:
        self.client.get("/", name="/ (dashboard)")

    @task(3)
    def patient_list(self) -> None:
        page = random.randint(1, PLAN["patient_pages"])
        self.client.get(f"/patients/?page={page}", name="/patients/?page=N")

    @task(4)
    def patient_detail(self) -> None:
        self.client.get(f"/patients/{self.patient()}/", name="/patients/{id}/")

    @task(2)
    def progress_json(self) -> None:
        pk = self.patient()
        self.client.get(f"/patients/{pk}/progress.json", name="/patients/{id}/progress.json")

    @task(2)
    def api_progress(self) -> None:
        pk = self.patient()
        self.client.get(f"/api/v1/patients/{pk}/progress/", name="/api/v1/patients/{id}/progress/")

    @task(2)
    def api_history(self) -> None:
        pk = self.patient()
        name = "/api/v1/patients/{id}/recordings/"
        self.client.get(f"/api/v1/patients/{pk}/recordings/", name=name)

    @task(2)
    def recording_page(self) -> None:
        self.client.get(f"/recordings/{self.recording()}/", name="/recordings/{id}/")

    @task(2)
    def recording_result(self) -> None:
        pk = self.recording()
        self.client.get(f"/recordings/{pk}/result.json", name="/recordings/{id}/result.json")


class Uploader(HttpUser):
    fixed_count = int(os.environ.get("LOAD_UPLOADERS", "20"))
    wait_time = between(0.5, 1.5)

    def on_start(self) -> None:
        slot = PLAN["uploaders"].pop()
        self.patient, self.uploads = slot["patient"], slot["files"]
        self.client.headers["Authorization"] = f"Token {slot['token']}"

    @task
    def upload_and_wait(self) -> None:
        item = random.choice(self.uploads)
        started = time.perf_counter()
        response = self.client.post(
            "/api/v1/recordings/",
            data={"patient": self.patient, "exercise": item["exercise"]},
            files={"file": (Path(item["file"]).name, unique_copy(item["file"]))},
            name="/api/v1/recordings/ (upload)",
        )
        if response.status_code != 201:
            return
        self.wait_for_result(response.json()["id"], started)

    def wait_for_result(self, pk: str, started: float) -> None:
        status = None
        while time.perf_counter() - started < RESULT_TIMEOUT_S:
            time.sleep(POLL_SECONDS)
            response = self.client.get(f"/api/v1/recordings/{pk}/", name="/api/v1/recordings/{id}/")
            status = response.json().get("status") if response.ok else None
            if status in ("succeeded", "failed"):
                break
        elapsed_ms = (time.perf_counter() - started) * 1000.0
        events.request.fire(
            request_type="RESULT",
            name="upload-to-result",
            response_time=elapsed_ms,
            response_length=0,
            exception=None if status == "succeeded" else RuntimeError(f"run ended {status}"),
            context={},
        )
