"""A therapist marks the reference's key poses as a user would: the page opens on the body part
that moves most, with axes in seconds and degrees, a 3D view of the reference at the pointer's
moment, checkboxes beside their body-part names, names typed for a kind of key pose kept after
saving, and the feedback grammar filled in with a guide to its syntax.

With E2E_DOCS=1 the page is saved to docs/img/keypose-page.png (README).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from tests.personas import PASSWORD, make_exercise, make_user

pytestmark = pytest.mark.e2e
DOCS = Path(__file__).resolve().parents[2] / "docs" / "img"
SESSION = "sessions/m01_s01_correct.bvh.gz"  # a ten-repetition deep squat


@pytest.fixture
def annotator(transactional_db, settings, tmp_path):
    from webapp.accounts.models import Clinic, Role

    settings.MEDIA_ROOT = tmp_path / "media"
    settings.PASSWORD_HASHERS = ["django.contrib.auth.hashers.MD5PasswordHasher"]
    clinic = Clinic.objects.create(name="Key-pose clinic")
    user = make_user("keyposes", clinic, Role.THERAPIST)
    exercise = make_exercise(clinic, source=SESSION)
    return user, exercise


def open_page(page, base_url: str, user, exercise) -> dict:
    page.goto(f"{base_url}/accounts/login/")
    page.fill("#id_username", user.username)
    page.fill("#id_password", PASSWORD)
    page.click("button[type=submit]")
    page.wait_for_url(lambda url: "/accounts/login" not in url)
    page.goto(f"{base_url}/exercises/{exercise.pk}/annotate/")
    page.wait_for_selector("#annotate[data-ready='1']", state="attached")
    return page.evaluate(
        "async () => (await fetch(document.getElementById('annotate').dataset.tutorUrl)).json()"
    )


def canvas(page) -> str:
    return page.evaluate("document.getElementById('pose-canvas').toDataURL()")


def hover_curve(page, fraction: float) -> None:
    box = page.locator("#curves").bounding_box()
    page.mouse.move(box["x"] + box["width"] * fraction, box["y"] + box["height"] * 0.5)


def test_key_pose_page_walk(page, live_server, annotator):
    user, exercise = annotator
    data = open_page(page, live_server.url, user, exercise)
    rig_names = set(data["joints"])

    # Opens on the body part that moves most (largest range of its angle), in plain words.
    shown = page.eval_on_selector("#joint", "s => s.value")
    spread = {j: np.ptp(data["angles_deg"][j]) for j in data["joints"][1:]}
    assert spread[shown] == max(spread.values()) and spread[shown] > 20
    options = page.eval_on_selector_all("#joint option", "os => os.map(o => o.textContent)")
    assert options[0] == data["labels"][shown] and not rig_names & set(options)

    # Axes with units: seconds along, degrees up, and their titles.
    texts = page.eval_on_selector_all("#curves text", "ts => ts.map(t => t.textContent)")
    assert any(t.endswith(" s") and t[:-2].replace(".", "").isdigit() for t in texts)
    assert any(t.endswith("°") for t in texts)
    assert "Time (seconds)" in texts and any("(degrees)" in t for t in texts)

    # The 3D view follows the pointer along the curve.
    hover_curve(page, 0.2)
    page.wait_for_timeout(300)
    before, first = canvas(page), page.evaluate("window.keyPosePage.cursor")
    hover_curve(page, 0.45)
    page.wait_for_function(f"window.keyPosePage.cursor !== {first}")
    page.wait_for_timeout(300)
    assert canvas(page) != before
    assert page.evaluate("window.keyPosePage.playback.frame") == page.evaluate(
        "window.keyPosePage.cursor"
    )
    assert page.inner_text("#pose-caption").startswith("The reference at ")

    # Each checkbox sits on the line of its own name.
    rows = page.locator("#joints label")
    assert rows.count() == len(data["body_parts"])
    names = [rows.nth(i).inner_text().strip() for i in range(rows.count())]
    assert len(set(names)) == len(names), "each body part is offered once"
    for i in (0, rows.count() // 2, rows.count() - 1):
        row, tick = rows.nth(i).bounding_box(), rows.nth(i).locator("input").bounding_box()
        assert (
            row["height"] < 40
            and abs((tick["y"] + tick["height"] / 2) - (row["y"] + row["height"] / 2)) < 6
        )
        assert rows.nth(i).inner_text().strip() not in rig_names

    # The grammar box holds a default grammar in plain words, checked valid, with a guide.
    grammar = page.input_value("#grammar")
    assert grammar.startswith("# Default feedback grammar") and "->" in grammar and 'F:"' in grammar
    assert page.is_visible("#grammar-default")
    assert not any(f"@{name}$" in grammar for name in rig_names)
    page.wait_for_function(
        "document.getElementById('grammar-status').textContent.startsWith('Valid')"
    )
    guide = page.inner_text("#grammar-guide")
    assert "type$2" in guide and "@left_knee$3" in guide and "->" in guide

    if os.environ.get("E2E_DOCS"):
        DOCS.mkdir(parents=True, exist_ok=True)
        hover_curve(page, 0.3)
        page.wait_for_timeout(400)
        page.screenshot(path=str(DOCS / "keypose-page.png"), full_page=True)

    # A name typed for a kind of key pose is kept, though no key pose was added after typing it.
    page.fill("#ltype", "2")
    page.fill("#lname", "deepest point")
    page.click("#save-landmarks")
    page.wait_for_function("document.getElementById('landmarks-status').textContent === 'Saved.'")
    exercise.refresh_from_db()
    assert exercise.landmark_type_names["2"] == "deepest point"
    page.reload()
    page.wait_for_selector("#annotate[data-ready='1']", state="attached")
    page.fill("#ltype", "2")
    page.dispatch_event("#ltype", "input")
    assert page.input_value("#lname") == "deepest point"
    names = page.eval_on_selector_all("#curves .mark-name", "ts => ts.map(t => t.textContent)")
    assert "deepest point" in names
