"""Issue 25: the plausibility check on upload. A file whose frame time no capture system
produces, or longer than the site's limits, is refused by the page and the API with the plain
reason, and nothing is stored; the limits come from the settings."""

from __future__ import annotations

import gzip
import re

import pytest

from tests.personas import fixture_bytes, make_exercise
from tests.webapp.test_api_uploads import api, post  # noqa: F401 (the API client fixture)
from tests.webapp.test_uploads import GOOD, assert_nothing_stored, upload


@pytest.fixture
def exercise(world):
    return make_exercise(world.clinic)


def good_text() -> str:
    return gzip.decompress(fixture_bytes(GOOD)).decode()


def with_frame_time(value: str) -> bytes:
    return re.sub(r"Frame Time:.*", f"Frame Time: {value}", good_text()).encode()


def test_the_page_refuses_a_frame_time_of_1000_with_the_reason(client, world, exercise, settings):
    client.force_login(world.therapist)
    response = upload(client, world.patient, exercise, with_frame_time("1000"), name="take.bvh")
    assert response.status_code == 400
    page = response.content.decode()
    assert "each frame lasts 1000 s" in page and "Export the recording again" in page
    assert_nothing_stored(settings)


def test_the_api_refuses_it_too(api, world, exercise, settings):  # noqa: F811
    response = post(api, world.patient, exercise, with_frame_time("1e-05"), name="take.bvh")
    assert response.status_code == 400
    assert "each frame lasts 1e-05 s" in response.json()["file"][0]["message"]
    assert_nothing_stored(settings)


def test_a_take_longer_than_the_site_allows_is_refused(client, world, exercise, settings):
    settings.RECORDING_MAX_SECONDS = 1.0
    client.force_login(world.therapist)
    response = upload(client, world.patient, exercise, fixture_bytes(GOOD))
    assert response.status_code == 400
    assert "at most 1.0 s can be analysed" in response.content.decode()
    assert_nothing_stored(settings)


def test_the_memory_estimate_uses_the_exercise_and_the_settings(client, world, exercise, settings):
    settings.RECORDING_MAX_ANALYSIS_BYTES = 1 << 20
    client.force_login(world.therapist)
    response = upload(client, world.patient, exercise, fixture_bytes(GOOD))
    assert response.status_code == 400
    assert "would need about" in response.content.decode()
    assert_nothing_stored(settings)
