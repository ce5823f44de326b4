"""Every page fits the screen it is read on, in a real browser with the demo clinic (issue 38):
every page the clinic's staff open, at a 768 px tablet, and every page a patient opens (and the
sign-in pages they reach first), at a 360 px phone, with the document no wider than the screen.
The staff's pages are also read on a 390 px phone: the document no wider than the screen and
nothing past its edge, except inside a box that scrolls sideways on its own (a wide table), which
says what it holds with text on the page and can be scrolled from the keyboard.
The patient's Help is the patients' guide: no therapist's words and no password.

The pages are named by their URL patterns, so a new page must be listed here (or among the
addresses that are no page, with the reason) or `test_every_url_is_a_listed_page_or_no_page`
fails. One server, one browser and one signed-in context per person; every page is visited and
the failure lists every page too wide, with its width.
"""

from __future__ import annotations

from dataclasses import dataclass
from urllib.parse import urlparse

import pytest
from django.urls import URLPattern, URLResolver, get_resolver, reverse

from tests.e2e.conftest import log_in

pytestmark = pytest.mark.e2e
THERAPIST_WORDS = ("a therapist's work", "tutor", "Build model", "BVH", "-pw")
WIDTHS = "() => [document.documentElement.scrollWidth, window.innerWidth]"
TABLET, PHONE, STAFF_PHONE = 768, 360, 390
# What makes a page hard to read on a phone, beyond its width: elements past the screen's edges
# that no box of their own scrolls to (clipped or widening the page), and boxes that scroll
# sideways without visible text saying what they hold (aria-labelledby) or without a keyboard stop.
UNREADABLE = """() => {
  const name = el => el.tagName.toLowerCase() + (el.id ? '#' + el.id : '')
    + [...el.classList].map(c => '.' + c).join('');
  const scrolls = el => el !== document.body && el !== document.documentElement
    && ['auto', 'scroll'].includes(getComputedStyle(el).overflowX);
  const shown = el => el.getBoundingClientRect().width > 0 && el.getBoundingClientRect().height > 0;
  const label = el => (el.getAttribute('aria-labelledby') || '').split(/\\s+/)
    .map(id => document.getElementById(id)).filter(l => l && shown(l))
    .map(l => l.innerText.trim()).join(' ');
  const found = [];
  for (const el of document.body.querySelectorAll('*')) {
    if (!shown(el) || ['TEXTAREA', 'SELECT', 'INPUT', 'OPTION'].includes(el.tagName)) continue;
    const box = el.getBoundingClientRect();
    if (box.right <= 0 || box.left >= innerWidth) continue;  // kept off screen on purpose
    // inside a chart, only its words: its lines and shapes are clipped to the plot on purpose
    if (el instanceof SVGElement && !['svg', 'text'].includes(el.tagName)) continue;
    let holder = el.parentElement;
    while (holder && !scrolls(holder)) holder = holder.parentElement;
    const outer = el.parentElement.getBoundingClientRect();
    // report the outermost element only (a chart's words one by one: their groups are skipped)
    const outermost = el.tagName === 'text' || (outer.right <= innerWidth + 1 && outer.left >= -1);
    if (!holder && outermost && (box.right > innerWidth + 1 || box.left < -1))
      found.push(`${name(el)} spans ${Math.round(box.left)}–${Math.round(box.right)} px`);
    if (scrolls(el) && el.scrollWidth > el.clientWidth + 1 && (!label(el) || el.tabIndex < 0))
      found.push(`${name(el)} scrolls without a visible label or keyboard stop`);
  }
  return found;
}"""

# URL name → who opens it: the staff's pages at the tablet's width (the clinic admin's own pages
# as the admin), the patient's at the phone's, the sign-in pages as a visitor at the phone's.
STAFF = {
    "dashboard:home": "demo-therapist",
    "help:guide": "demo-therapist",
    "patients:list": "demo-therapist",
    "patients:create": "demo-therapist",
    "patients:detail": "demo-therapist",
    "patients:edit": "demo-therapist",
    "patients:prescribe": "demo-therapist",
    "patients:compare": "demo-therapist",
    "reports:progress": "demo-therapist",
    "reports:progress-print": "demo-therapist",
    "exercises:list": "demo-therapist",
    "exercises:create": "demo-therapist",
    "exercises:detail": "demo-therapist",
    "exercises:edit": "demo-therapist",
    "exercises:reference": "demo-therapist",
    "exercises:annotate": "demo-therapist",
    "recordings:upload": "demo-therapist",
    "recordings:detail": "demo-therapist",
    "recordings:move": "demo-therapist",
    "recordings:delete": "demo-therapist",
    "reports:recording-print": "demo-therapist",
    "live:page": "demo-therapist",
    "live:watch": "demo-therapist",
    "camera:page": "demo-therapist",
    "accounts:invite-patient": "demo-therapist",
    "accounts:tokens": "demo-therapist",
    "accounts:2fa-setup": "demo-therapist",
    "accounts:password-change": "demo-therapist",
    "accounts:password-changed": "demo-therapist",
    "accounts:team": "demo-admin",
    "audit:events": "demo-admin",
    "recordings:deleted": "demo-admin",
}
PATIENT = {
    "dashboard:home": "demo-patient",
    "dashboard:my-progress": "demo-patient",
    "help:guide": "demo-patient",
    "recordings:upload": "demo-patient",
    "recordings:detail": "demo-patient",
    "camera:page": "demo-patient",
    "live:page": "demo-patient",
    "accounts:password-change": "demo-patient",
    "accounts:login": "",
    "accounts:password-reset": "",
    "accounts:password-reset-sent": "",
    "accounts:password-reset-complete": "",
    "accounts:invitation": "",
    "accounts:new-password": "",
}
# Addresses that are no page of their own, and why.
NOT_PAGES = {
    "healthz": "a health check for the server's monitor",
    "favicon": "an icon",
    "help:image": "a picture of the guide",
    "accounts:logout": "signs out and goes to the sign-in page",
    "accounts:2fa-verify": "the second sign-in step, only inside a sign-in with two factors",
    "accounts:password-reset-confirm": "the e-mailed link's page; its set form is new-password's",
    "audit:export": "CSV",
    "patients:progress": "JSON",
    "patients:history-csv": "CSV",
    "exercises:reference-data": "JSON",
    "exercises:model-status": "JSON",
    "exercises:tutor-data": "JSON",
    "recordings:status": "JSON",
    "recordings:result": "JSON",
    "recordings:corrections": "JSON",
    "recordings:video": "the recording's video file",
    "live:status": "JSON",
    "reports:playback": "JSON",
    "reports:playback-bin": "binary positions",
    "reports:recording-pdf": "PDF",
    "reports:progress-pdf": "PDF",
    "dashboard:my-reference": "JSON",
}
# Forms posted from other pages, which answer with a redirect or JSON.
POSTED = {
    "patients:archive", "patients:add-goal", "exercises:archive", "exercises:add-rule",
    "exercises:build", "exercises:landmarks", "exercises:grammar", "recordings:rerun",
    "recordings:confirm", "recordings:label", "recordings:restore", "recordings:add-note",
    "live:start", "live:replay", "camera:start", "dashboard:my-effort", "accounts:token-revoke",
    "accounts:team-deactivate", "accounts:team-reactivate", "accounts:team-password-link",
    "accounts:team-withdraw-link",
}  # fmt: skip


def url_names(resolver: URLResolver | None = None, namespace: str = "") -> set[str]:
    """Every named URL of the site but the API's and Django admin's (which speak to programs
    and to the software's operators), with its namespace ("patients:detail")."""
    names = set()
    for entry in (resolver or get_resolver()).url_patterns:
        if isinstance(entry, URLResolver):
            inner = ":".join(n for n in (namespace, entry.namespace or "") if n)
            if entry.namespace != "admin":
                names |= url_names(entry, inner)
        elif isinstance(entry, URLPattern):
            name = entry.name or ""  # unnamed: the uploaded files, served while developing
            if name and not name.startswith("api") and "api-" not in name:
                names.add(f"{namespace}:{name}" if namespace else name)
    return names


def test_every_url_is_a_listed_page_or_no_page():
    listed = set(STAFF) | set(PATIENT) | set(NOT_PAGES) | POSTED
    assert url_names() - listed == set(), "list the new page in STAFF, PATIENT or NOT_PAGES"
    assert listed - url_names() == set(), "a listed page no longer exists"


@dataclass(frozen=True)
class Demo:
    """The demo objects the pages are about: the demo patient's own."""

    patient: str
    exercise: str
    recording: str
    prescription: str
    live: str
    invitation: str
    password_link: str


def demo_objects() -> Demo:
    from webapp.accounts import invitations
    from webapp.accounts.models import Role, User
    from webapp.live.services import create_session
    from webapp.patients.models import Patient

    therapist = User.objects.get(username="demo-therapist")
    patient = User.objects.get(username="demo-patient").patient_profile
    prescription = patient.prescriptions.first()
    recording = patient.recordings.order_by("-uploaded_at").first()
    live = create_session(patient=patient, exercise=prescription.exercise, user=therapist)
    other = Patient.objects.filter(clinic=patient.clinic, user=None).first()
    _, invitation = invitations.create_invitation(therapist, str(Role.PATIENT), other)
    admin = User.objects.get(username="demo-admin")
    _, password_link = invitations.create_password_link(admin, therapist)
    return Demo(
        str(patient.pk), str(prescription.exercise.pk), str(recording.pk), str(prescription.pk),
        str(live.pk), invitation, password_link,
    )  # fmt: skip


def path_of(name: str, demo: Demo) -> str:
    """The page's address for the demo objects."""
    about = {
        "patients": demo.patient, "reports:progress": demo.patient, "exercises": demo.exercise,
        "recordings": demo.recording, "reports:recording": demo.recording, "live": demo.live,
        "camera": demo.prescription, "accounts:invite-patient": demo.patient,
        "accounts:invitation": demo.invitation, "accounts:new-password": demo.password_link,
    }  # fmt: skip
    for prefix, value in sorted(about.items(), key=lambda item: -len(item[0])):
        if name.startswith(prefix):
            try:
                return reverse(name, args=[value])
            except Exception:  # a list or form of that app takes no id
                break
    return reverse(name)


def too_wide(browser, base_url: str, pages: dict[str, str], width: int, demo: Demo) -> dict:
    """Each person's pages at ``width``: those wider than the screen (address → [document
    width, screen width]) and those that did not open (address → [status, where it went]).
    At the staff's phone width, also what is unreadable (address → what, where)."""
    found: dict[str, object] = {}
    for username in dict.fromkeys(pages.values()):
        context = browser.new_context(viewport={"width": width, "height": 900})
        page = context.new_page()
        page.set_default_timeout(60_000)
        try:
            if username:
                log_in(page, base_url, username)
            for name in (n for n, user in pages.items() if user == username):
                path = path_of(name, demo)
                where = f"{username or 'visitor'} {path} at {width} px"
                answer = page.goto(base_url + path)
                if answer is None or answer.status != 200 or urlparse(page.url).path != path:
                    # not opened, or sent elsewhere (the sign-in page): that page is not measured
                    found[where] = [answer and answer.status, page.url]
                    continue
                page.wait_for_load_state("load")
                scroll, inner = page.evaluate(WIDTHS)
                unreadable = page.evaluate(UNREADABLE) if width == STAFF_PHONE else []
                if scroll > inner or unreadable:
                    found[where] = [scroll, inner, *unreadable[:6]]
        finally:
            context.close()
    return found


def test_staff_pages_at_768_and_390_and_patient_pages_at_360(browser, live_server, demo):
    objects = demo_objects()
    wide = too_wide(browser, live_server.url, STAFF, TABLET, objects)
    wide |= too_wide(browser, live_server.url, STAFF, STAFF_PHONE, objects)
    wide |= too_wide(browser, live_server.url, PATIENT, PHONE, objects)
    assert wide == {}, (
        "too wide or unreadable ([document, screen] px, then what sticks out or scrolls "
        "unlabelled) or not opened ([status, address])"
    )
    the_patients_help_is_their_own_guide(browser, live_server)


def the_patients_help_is_their_own_guide(browser, live_server) -> None:
    context = browser.new_context(viewport={"width": PHONE, "height": 900})
    page = context.new_page()
    try:
        log_in(page, live_server.url, "demo-patient")
        page.goto(f"{live_server.url}/help/")
        text = page.locator("main").inner_text()
        assert "How to record a session" in text and "demonstration" in text
        found = [w for w in THERAPIST_WORDS if w.lower() in text.lower()]
        assert found == [] and "password (" not in text, found
    finally:
        context.close()
