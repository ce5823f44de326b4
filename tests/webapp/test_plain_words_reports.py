"""The recording pages and the PDF reports speak plain words (issue 23, item 7).

The demo clinic is loaded (its recordings analysed in-process), then for every analysed demo
recording, of all three demo exercises, the recording page (visible text and the words a pointer
or a screen reader shows: titles and labels), its printable page and its PDF, and each patient's
progress PDF are searched for the software's own words: stage and method names, rig joint names
and field names. The PDFs' text is read back with pypdf, as a reader would copy it.
"""

from __future__ import annotations

import io
import re
from html.parser import HTMLParser
from pathlib import Path

import pytest
from django.conf import settings as django_settings
from django.core.management import call_command
from django.urls import reverse
from pypdf import PdfReader

from analysis.pipeline.stage_order import ORDER
from tests.webapp.test_plain_words import rig_joint_names
from webapp.reports.templatetags.timeline import STAGE_WORDS, stage_words

# What the software calls things, never what a therapist reads (case-insensitive phrases).
INTERNAL_PHRASES = (
    "key poses as found", "candidate moment", "moved by refining", "refining", "order check",
    "GBDTW", "DTW", "landmark", "C4.5", "AdaBoost", "gamma_", "rom_",
)  # fmt: skip
# Joint names of the common rigs besides the demo's own (CMU, Mixamo), as words.
OTHER_RIGS = (
    "LeftUpLeg", "RightUpLeg", "LeftForeArm", "lhumerus", "rhumerus", "lowerneck", "upperneck",
    "lfemur", "rfemur", "ltibia", "rtibia", "lradius", "rradius",
)  # fmt: skip
# A field name: words joined by underscores ("tutor_adjusted", "pass_threshold").
SNAKE = re.compile(r"\b[a-z][a-z0-9]*(?:_[a-z0-9]+)+\b")
# What the page shows besides the text between tags.
SHOWN_ATTRIBUTES = ("title", "aria-label", "alt", "placeholder")
INVISIBLE = {"script", "style", "template", "noscript", "head"}


class ShownText(HTMLParser):
    """Visible text of a page plus the attributes a pointer or screen reader shows."""

    def __init__(self) -> None:
        super().__init__()
        self.parts: list[str] = []
        self.hidden = 0

    def handle_starttag(self, tag, attrs):
        if tag in INVISIBLE:
            self.hidden += 1
        self.parts += [value for name, value in attrs if name in SHOWN_ATTRIBUTES and value]

    def handle_endtag(self, tag):
        if tag in INVISIBLE:
            self.hidden = max(0, self.hidden - 1)

    def handle_data(self, data):
        if not self.hidden and data.strip():
            self.parts.append(data.strip())


def shown_text(html: str) -> str:
    parser = ShownText()
    parser.feed(html)
    return " | ".join(parser.parts)


def pdf_text(body: bytes) -> str:
    assert body.startswith(b"%PDF")
    return " | ".join(page.extract_text() for page in PdfReader(io.BytesIO(body)).pages)


def download_pdf(client, url: str, capture) -> bytes:
    """The PDF at `url`: the first request has the worker make it (after commit), the second
    downloads it."""
    with capture(execute=True):
        assert client.get(url).status_code == 202
    response = client.get(url)
    assert response.status_code == 200
    return b"".join(response.streaming_content)


def internal_words(text: str, joints: set[str], allowed: set[str] = frozenset()) -> list[str]:
    """Every internal word in `text`; `allowed` are the user's own words (file names)."""
    for own in allowed:
        text = text.replace(own, " ")
    found = [p for p in INTERNAL_PHRASES if p.lower() in text.lower()]
    found += [j for j in (*joints, *OTHER_RIGS) if re.search(rf"\b{re.escape(j)}\b", text)]
    return found + SNAKE.findall(text)


def test_the_checker_finds_each_kind_of_internal_word():
    joints = {"LeftUpperArm"}
    text = (
        "key poses as found (2; 64 candidate moments considered) | Moved by refining | "
        "Order check | GBDTW | landmark | C4.5 + AdaBoost | gamma_hat | LeftUpperArm | "
        "lowerneck | pass_threshold"
    )
    assert set(internal_words(text, joints)) == {
        "key poses as found", "candidate moment", "moved by refining", "refining",
        "order check", "GBDTW", "DTW", "landmark", "C4.5", "AdaBoost", "gamma_",
        "LeftUpperArm", "lowerneck", "gamma_hat", "pass_threshold",
    }  # fmt: skip
    plain = "Key body positions the analysis found: 2 · left upper arm, 37.8 s, score 74 / 100"
    assert internal_words(plain, joints) == []
    # A recording's own file name is the user's word, not the software's.
    assert internal_words("m01_s02_correct.bvh", joints, {"m01_s02_correct.bvh"}) == []


def test_shown_text_includes_titles_and_labels_not_scripts():
    html = '<div aria-label="Order check"><b title="as found">x</b><script>a_b()</script></div>'
    assert shown_text(html) == "Order check | as found | x"


@pytest.fixture
def demo(client, settings):
    settings.DEMO_ALLOWED = True
    call_command("load_demo")
    assert client.login(username="demo-therapist", password="demo-therapist-pw")
    return client


@pytest.mark.django_db
def test_recording_pages_and_reports_of_the_demo_speak_plain_words(
    demo, django_capture_on_commit_callbacks
):
    from webapp.patients.models import Patient
    from webapp.recordings.models import Recording

    capture = django_capture_on_commit_callbacks
    joints = rig_joint_names()
    recordings = [r for r in Recording.objects.all() if r.latest_succeeded_run()]
    # Analysed recordings of every demo exercise are read.
    assert len({r.exercise.name for r in recordings}) == 3
    problems: dict[str, list[str]] = {}
    for recording in recordings:
        own = {recording.original_name} if recording.original_name else set()
        html = {
            name: demo.get(reverse(name, args=[recording.pk])).content.decode()
            for name in ("recordings:detail", "reports:recording-print")
        }
        pages = {
            "page": shown_text(html["recordings:detail"]),
            "printable": shown_text(html["reports:recording-print"]),
            "pdf": pdf_text(
                download_pdf(demo, reverse("reports:recording-pdf", args=[recording.pk]), capture)
            ),
        }
        # The page shows the timeline and the PDF its rows: the crawl reads what it must check.
        assert "Repetitions" in pages["pdf"] and "time (s)" in pages["page"]
        for where, text in pages.items():
            if words := internal_words(text, joints, own):
                problems[f"{recording.exercise.name} {recording.pk} {where}"] = sorted(set(words))
    for patient in Patient.objects.all():
        url = reverse("reports:progress-pdf", args=[patient.pk])
        text = pdf_text(download_pdf(demo, url, capture))
        assert "Sessions" in text
        if words := internal_words(text, joints):
            problems[f"progress PDF of {patient.display_name}"] = sorted(set(words))
    assert not problems, problems


def test_every_stage_the_progress_line_names_is_in_plain_words():
    # While an analysis runs, the recording page (and run_status.js, polling) names its stage.
    said = [stage_words(stage.label) for stage in ORDER] + [stage_words(s) for s in STAGE_WORDS]
    assert not [s for s in said if internal_words(s, set())], said
    script = (Path(django_settings.BASE_DIR) / "webapp/static/js/run_status.js").read_text()
    # The script that updates the line while polling says the same words as the page.
    assert all(f'"{words}"' in script for words in STAGE_WORDS.values())
