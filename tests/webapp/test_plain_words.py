"""Every page the demo's therapist, patient and clinic admin can reach speaks plain words.

The demo clinic is loaded, then each user follows every same-site link from the home page (GET
only; logging out, downloads, the API and its documentation left out: the API speaks to programs)
and the visible text of each page is searched for what only the software should say: the demo
rigs' joint names ("LeftUpperArm"), `tutor_adjusted`, γ, "channels", record ids, "tutor", the
analysis's own counts ("key poses the analysis found"), "latency p95", and the demo accounts'
passwords (a production clinic's pages would show them too).

The exercise's model performance has one name per reader: "the reference" on the staff's pages
(in their own words: the sentences said to the patient, quoted on those pages inside
`data-patient-words`, keep the patient's name), "the demonstration" on the patient's pages.
"""

from __future__ import annotations

import re
from html.parser import HTMLParser
from urllib.parse import urljoin, urlparse

import numpy as np
import pytest
from django.core.management import call_command

from analysis.bvh import Skeleton
from webapp.recordings.words import body_part, file_problem, key_pose_name, plural, rig_table

USERS = ("demo-therapist", "demo-patient", "demo-admin")
SKIPPED = re.compile(r"/logout|/api/|/admin/|\.(csv|pdf|json|bin|bvh|gz)$|/static/|/media/")
INVISIBLE = {"script", "style", "template", "noscript", "head"}
VOID = {"area", "base", "br", "col", "embed", "hr", "img", "input", "link", "meta", "source", "wbr"}
ID = re.compile(r"\b[0-9a-f]{8}-[0-9a-f]{2,4}", re.IGNORECASE)  # whole or cut short
MAX_PAGES = 400


class Page(HTMLParser):
    """The visible text and the followable links of one HTML page; `own` is the visible text
    outside the words quoted as said to the patient (elements with `data-patient-words`)."""

    def __init__(self) -> None:
        super().__init__()
        self.links: list[str] = []
        self.text: list[str] = []
        self.own: list[str] = []
        self.hidden = 0
        self.open: list[tuple[str, bool]] = []  # open elements: tag, quotes the patient's words

    def handle_starttag(self, tag, attrs):
        values = dict(attrs)
        if tag in INVISIBLE:
            self.hidden += 1
        if tag == "a" and values.get("href") and "download" not in values:
            self.links.append(values["href"])
        if tag not in VOID:
            self.open.append((tag, "data-patient-words" in values))

    def handle_endtag(self, tag):
        if tag in INVISIBLE:
            self.hidden = max(0, self.hidden - 1)
        if any(name == tag for name, _ in self.open):
            while self.open and self.open.pop()[0] != tag:
                pass

    def handle_data(self, data):
        if not self.hidden and data.strip():
            self.text.append(data.strip())
            if not any(quoted for _, quoted in self.open):
                self.own.append(data.strip())


def crawl(
    client, html: dict[str, str] | None = None, own: dict[str, str] | None = None
) -> dict[str, str]:
    """Visible text of every page reachable from "/" by same-site links (path → text); `html`,
    when given, receives each HTML page's whole markup (path → markup), `own` each page's text
    outside the patient's quoted words (path → text)."""
    seen: dict[str, str] = {}
    todo = ["/"]
    while todo and len(seen) < MAX_PAGES:
        path = todo.pop()
        if path in seen:
            continue
        response = client.get(path)
        assert response.status_code in (200, 302), f"{path}: {response.status_code}"
        seen[path] = ""
        if response.status_code != 200 or "html" not in response.get("Content-Type", ""):
            continue
        page = Page()
        page.feed(response.content.decode())
        if html is not None:
            html[path] = response.content.decode()
        seen[path] = " | ".join(page.text)
        if own is not None:
            own[path] = " | ".join(page.own)
        for href in page.links:
            parts = urlparse(urljoin(path, href))
            if parts.scheme not in ("", "http") or parts.netloc not in ("", "testserver"):
                continue
            target = parts.path + (f"?{parts.query}" if parts.query else "")
            if not SKIPPED.search(parts.path) and target not in seen:
                todo.append(target)
    return seen


def rig_joint_names() -> set[str]:
    """The demo tutors' joint names that are not words ("LeftUpperArm", "HeadTip")."""
    from webapp.exercises.models import Exercise

    names = {n for e in Exercise.objects.all() for n in e.tutor_motion().skeleton.names}
    return {n for n in names if re.search(r"[a-z][A-Z]|_|\d", n)}


# Words a new user found on the pages (issue 38): the software's name for the reference, the
# analysis's own counts, the live page's timing figure, and the demo accounts' passwords (which
# a production clinic's pages would show as well).
UNPLAIN = re.compile(
    # "{tutor}" alone is allowed: a placeholder of the feedback rules' language, not a word.
    r"(?<!\{)\btutors?\b(?!\})|key poses the analysis found|moments that looked like one"
    r"|latency p95"
    r"|demo-(therapist|patient|admin)-pw",
    re.IGNORECASE,
)


# The staff's name for the exercise's model performance is "the reference"; the patient's is "the
# demonstration" (issue 38: the same thing was called tutor, reference and demonstration).
NOT_STAFF_NAME = re.compile(
    r"\bdemonstrations?\b|\breference (recording|movement|motion)s?\b", re.I
)
NOT_PATIENT_NAME = re.compile(r"\breferences?\b|\breference's\b", re.IGNORECASE)


def other_names(text: str, patient: bool) -> list[str]:
    """Names of the reference a page should not use: `text` is a patient's page's visible text,
    or a staff page's own words (without the sentences quoted as said to the patient)."""
    wrong = NOT_PATIENT_NAME if patient else NOT_STAFF_NAME
    return [m.group(0) for m in wrong.finditer(text)]


def internal_words(text: str, joints: set[str]) -> list[str]:
    found = [j for j in joints if re.search(rf"\b{re.escape(j)}\b", text)]
    found += [w for w in ("tutor_adjusted", "γ") if w in text]
    found += re.findall(r"\bchannels?\b", text, re.IGNORECASE)
    found += [m.group(0) for m in ID.finditer(text)]
    found += [m.group(0) for m in UNPLAIN.finditer(text)]
    return found


@pytest.mark.django_db
def test_no_page_of_the_demo_shows_internal_words(client, settings):
    settings.DEMO_ALLOWED = True
    call_command("load_demo")
    joints = rig_joint_names()
    assert {"LeftUpperArm", "RightLowerLeg", "HeadTip"} <= joints  # the demo rigs' own names
    problems = {}
    pages = 0
    for username in USERS:
        assert client.login(username=username, password=f"{username}-pw")
        own: dict[str, str] = {}
        texts = crawl(client, own=own)
        pages += len(texts)
        for path, text in texts.items():
            # /my/… pages (the camera page the staff may open too) speak to the patient.
            patient = username == "demo-patient" or path.startswith("/my/")
            words = internal_words(text, joints)
            words += other_names(text if patient else own.get(path, ""), patient)
            if words:
                problems[f"{username} {path}"] = sorted(set(words))
        client.logout()
    # The walk reaches the recordings, the patients' pages and the reports of the demo data.
    assert pages > 60
    by_word: dict[str, list[str]] = {}
    for page, words in problems.items():
        for word in words:
            by_word.setdefault(word, []).append(page)
    assert not problems, {word: (len(found), found[:3]) for word, found in by_word.items()}


def test_the_checker_finds_what_it_looks_for():
    joints = {"LeftUpperArm", "HeadTip"}
    text = "Performance level γ | LeftUpperArm | tutor_adjusted | 57 channels | 0d1511dd-5c0…"
    assert sorted(internal_words(text, joints)) == sorted(
        ["LeftUpperArm", "tutor_adjusted", "γ", "channels", "0d1511dd-5c0"]
    )
    text = "Tutor frame | key poses the analysis found: 0 | latency p95 | password demo-admin-pw"
    text += " | rules may say {tutor}"
    assert sorted(internal_words(text, joints)) == sorted(
        ["Tutor", "key poses the analysis found", "latency p95", "demo-admin-pw"]
    )
    assert internal_words("Left upper arm, level 0.8, 3 repetitions, 37.8 s", joints) == []


def test_each_reader_has_one_name_for_the_reference():
    staff = "Replace the reference recording | Play the reference | the demonstration, kept in step"
    assert other_names(staff, patient=False) == ["reference recording", "demonstration"]
    assert other_names("Key poses of the reference | the reference's pose", patient=False) == []
    patient = "Watch the demonstration | your movement adjusted to the reference"
    assert other_names(patient, patient=True) == ["reference"]
    assert other_names("Watch the demonstration and do the same", patient=True) == []


def test_the_staffs_own_words_leave_out_what_the_patient_is_told():
    page = Page()
    page.feed(
        "<main><h3>Feedback</h3><ol data-patient-words><li>Stop where the demonstration stops"
        '<br></li></ol><p>Replace the reference</p><textarea data-patient-words>F:"x"</textarea>'
        "<input name=a></main>"
    )
    assert page.own == ["Feedback", "Replace the reference"]
    assert page.text == ["Feedback", "Stop where the demonstration stops", "Replace the reference",
                         'F:"x"']  # fmt: skip


@pytest.mark.parametrize(
    ("joint", "words"),
    [
        ("LeftUpperArm", "left upper arm"),  # UI-PRMD (the demo)
        ("LeftCollar", "left collarbone"),
        ("HeadTip", "top of the head"),
        ("UpperArm_L", "left upper arm"),  # Bandai-Namco
        ("LowerLeg_R", "right lower leg"),
        ("joint_Root", "body position"),
        ("RightUpLeg", "right thigh"),  # CMU / Mixamo
        ("mixamorig:LeftForeArm", "left forearm"),
        ("Spine1", "middle back"),
        ("LThigh", "left thigh"),  # OptiTrack
    ],
)
def test_rig_joint_names_become_body_parts(joint, words):
    assert body_part(joint) == words


def bandai_skeleton() -> Skeleton:
    """Bandai-Namco's shape: a floor-level root with zero offset whose only child is the hips."""
    joints = [  # name, parent, offset (cm, y up, x to the left)
        ("joint_Root", -1, (0, 0, 0)), ("Hips", 0, (0, 95, 0)), ("Spine", 1, (0, 10, 0)),
        ("Chest", 2, (0, 25, 0)), ("Neck", 3, (0, 20, 0)), ("Head", 4, (0, 10, 0)),
    ]  # fmt: skip
    for side, x in (("L", 1), ("R", -1)):
        base = len(joints)
        joints += [
            (f"Shoulder_{side}", 3, (4 * x, 18, 0)), (f"UpperArm_{side}", base, (14 * x, 0, 0)),
            (f"LowerArm_{side}", base + 1, (28 * x, 0, 0)),
            (f"Hand_{side}", base + 2, (25 * x, 0, 0)),
            (f"UpperLeg_{side}", 1, (9 * x, -5, 0)), (f"LowerLeg_{side}", base + 4, (0, -42, 0)),
            (f"Foot_{side}", base + 5, (0, -40, 0)), (f"Toes_{side}", base + 6, (0, -6, 12)),
        ]  # fmt: skip
    return Skeleton(
        names=tuple(name for name, _, _ in joints),
        parents=np.array([parent for _, parent, _ in joints], dtype=np.int64),
        offsets=np.array([offset for _, _, offset in joints], dtype=np.float64),
        channels=(("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation"),)
        * len(joints),
        end_site_parents=np.array([5], dtype=np.int64),
        end_site_offsets=np.array([[0.0, 12.0, 0.0]]),
    )


def test_a_rig_table_settles_names_by_the_rigs_structure():
    table = rig_table(bandai_skeleton())
    assert table["joint_Root"] == "body position"
    assert table["Hips"] == "hips"
    # With an upper-arm joint below it, a rig's "Shoulder" is the collarbone (by name alone, the
    # upper arm, as in CMU rigs).
    assert body_part("Shoulder_L") == "left upper arm"
    assert (table["Shoulder_L"], table["UpperArm_R"]) == ("left collarbone", "right upper arm")
    assert all(not re.search(r"[a-z][A-Z]|_", label) for label in table.values())


def test_counts_key_poses_and_file_messages_in_plain_words():
    assert (plural(1, "repetition"), plural(3, "repetition")) == ("1 repetition", "3 repetitions")
    assert key_pose_name(2, {"2": "end of range"}) == "end of range"
    assert key_pose_name(2, {"2": "key pose 2"}) == "second marked position of the movement"
    message = file_problem("line 9: frame line has 5 values but the skeleton has 57 channels")
    assert "channel" not in message and "57 per frame" in message
