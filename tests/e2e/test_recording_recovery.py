"""Recovering from a mistaken upload in a real browser (issue 25): the demo therapist moves a
recording to another exercise (it is analysed again) and deletes one after confirming; the clinic
admin restores it. The audit log holds each act. The charts of the recording page carry no link
to Plotly's cloud and no Plotly logo."""

from __future__ import annotations

import pytest

from tests.e2e.conftest import log_in

pytestmark = pytest.mark.e2e

CLOUD = "a[href*='plot.ly'], a[href*='plotly.com'], a[href*='chart-studio'], .modebar-btn--logo"


def demo_recording(exercise: str):
    from webapp.recordings.models import Recording

    return (
        Recording.objects.filter(exercise__name=exercise, runs__status="succeeded")
        .select_related("patient")
        .order_by("-uploaded_at")
        .first()
    )


def audit_actions(recording) -> list[tuple[str, str]]:
    from webapp.audit.models import AuditEvent

    rows = AuditEvent.objects.filter(object_type="Recording", object_id=str(recording.pk))
    return list(rows.exclude(action="read").order_by("id").values_list("action", "username"))


def assert_charts_stay_on_the_site(page, chart: str) -> None:
    page.wait_for_selector(f"#{chart} .modebar-btn", state="attached")
    page.hover(f"#{chart}")  # the mode bar shows on hover
    buttons = page.eval_on_selector_all(
        ".js-plotly-plot .modebar-btn", "bs => bs.map(b => b.getAttribute('data-title'))"
    )
    assert "Download plot as a PNG" in buttons or len(buttons) >= 3, buttons  # it is drawn
    assert not any("share" in (title or "").lower() for title in buttons), buttons
    assert page.locator(CLOUD).count() == 0
    hrefs = page.eval_on_selector_all(".js-plotly-plot a[href]", "as => as.map(a => a.href)")
    site = page.url.split("/")[:3]
    assert all(href.split("/")[:3] == site for href in hrefs), hrefs


def test_move_delete_and_restore_a_recording(page, live_server, demo):
    recording = demo_recording("Deep squat")
    log_in(page, live_server.url)
    page.goto(f"{live_server.url}/recordings/{recording.pk}/")
    page.wait_for_selector("#viewer[data-ready='1']")
    assert_charts_stay_on_the_site(page, "chart-angles")
    page.goto(f"{live_server.url}/patients/{recording.patient_id}/progress/")
    assert_charts_stay_on_the_site(page, "chart-score")
    page.goto(f"{live_server.url}/recordings/{recording.pk}/")

    page.click("#recording-recovery summary")
    page.select_option("#move-form #id_exercise", label="Sit to stand")
    page.click("#move-form button[type=submit]")
    page.wait_for_selector(".messages >> text=Recording moved")
    assert page.inner_text("h1").startswith("Sit to stand")
    recording.refresh_from_db()
    assert recording.exercise.name == "Sit to stand" and recording.runs.count() == 2
    assert audit_actions(recording) == [("update", "demo-therapist")]

    page.click("#recording-recovery summary")
    page.click("#delete-recording")
    page.wait_for_selector("text=Delete this recording?")
    page.click("#confirm-delete")
    page.wait_for_selector(".messages >> text=Recording deleted")
    assert f"/recordings/{recording.pk}/" not in page.content()  # gone from the patient's page
    assert page.goto(f"{live_server.url}/recordings/{recording.pk}/").status == 404
    assert audit_actions(recording)[-1] == ("delete", "demo-therapist")

    page.context.clear_cookies()  # signed out
    log_in(page, live_server.url, "demo-admin")
    page.click(".usermenu summary")
    page.click("text=Deleted recordings")
    row = page.locator("#deleted-recordings tr", has_text=recording.patient.display_name)
    assert "Sit to stand" in row.inner_text()
    row.locator("button", has_text="Restore").click()
    page.wait_for_selector(".messages >> text=restored")
    assert audit_actions(recording)[-1] == ("update", "demo-admin")
    page.goto(f"{live_server.url}/recordings/{recording.pk}/")
    assert page.inner_text("h1").startswith("Sit to stand")
