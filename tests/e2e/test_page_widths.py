"""Every page fits the screen it is read on, in a real browser with the demo clinic: each page a
therapist reaches (one of each kind) at a 768 px tablet with the document no wider than the
screen, and the patient's pages at a 360 px phone. The patient's Help is the patients' guide:
no therapist's words and no password."""

from __future__ import annotations

import re
from urllib.parse import urljoin, urlparse

import pytest

from tests.e2e.conftest import log_in

pytestmark = pytest.mark.e2e
SKIPPED = re.compile(r"/logout|/api/|/admin/|\.(csv|pdf|json|bin|bvh|gz|png|svg)$|/static/|/media/")
KIND = re.compile(r"[0-9a-f]{8}-[0-9a-f-]{27}")  # pages of one kind differ only by their ids
THERAPIST_WORDS = ("a therapist's work", "tutor", "Build model", "BVH", "-pw")
WIDTHS = "() => [document.documentElement.scrollWidth, window.innerWidth]"
LINKS = "() => [...document.querySelectorAll('a[href]')].filter(a => !a.hasAttribute('download'))" \
    ".map(a => a.getAttribute('href'))"  # fmt: skip


def too_wide(page, base_url: str, limit: int = 40) -> dict[str, list[int]]:
    """Walk one page of each kind from the home page; the pages wider than the screen."""
    todo, kinds, wide = ["/"], set(), {}
    while todo and len(kinds) < limit:
        path = todo.pop(0)
        kind = KIND.sub("ID", path)
        if kind in kinds:
            continue
        kinds.add(kind)
        answer = page.goto(base_url + path)
        if (
            answer is None
            or answer.status != 200
            or "html" not in answer.headers.get("content-type", "")
        ):
            continue
        page.wait_for_load_state("load")
        scroll, inner = page.evaluate(WIDTHS)
        if scroll > inner:
            wide[path] = [scroll, inner]
        for href in page.evaluate(LINKS):
            parts = urlparse(urljoin(path, href))
            if parts.netloc not in ("", urlparse(base_url).netloc) or SKIPPED.search(parts.path):
                continue
            if KIND.sub("ID", parts.path) not in kinds:
                todo.append(parts.path)
    assert len(kinds) > 4, kinds  # a patient reaches their home, progress, sessions, upload
    return wide


def test_therapist_pages_at_768_and_patient_pages_at_360(browser, live_server, demo):
    for username, width in (("demo-therapist", 768), ("demo-patient", 360)):
        context = browser.new_context(viewport={"width": width, "height": 900})
        page = context.new_page()
        page.set_default_timeout(60_000)
        try:
            log_in(page, live_server.url, username)
            assert too_wide(page, live_server.url) == {}, username
            if username == "demo-patient":
                page.goto(f"{live_server.url}/help/")
                text = page.locator("main").inner_text()
                assert "How to record a session" in text and "demonstration" in text
                found = [w for w in THERAPIST_WORDS if w.lower() in text.lower()]
                assert found == [] and "password (" not in text, found
        finally:
            context.close()
