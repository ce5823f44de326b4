"""The body parts the key-pose page and the rule picker offer: each once, in plain words.

A rig often has two joints that read as one body part: a zero-length connector ("LHipJoint")
above the thigh joint ("LeftUpLeg"), or two chest joints ("Chest", "Chest2"). The page offers one
joint per body part, the one a therapist sees move as that segment: the joint the rig's structure
names for that part (`analysis.bvh.rigs.identify`), else one that is not a zero-length connector,
else the first in the file. A tick on "left thigh" stores that joint, so it reads back the same.
"""

from __future__ import annotations

import re
from collections.abc import Iterable

import numpy as np

from analysis.bvh import Skeleton
from analysis.bvh.rigs import identify
from webapp.recordings.words import rig_table

SIDES = ("left", "right")
# Words some rigs write as one ("lowerneck"): split so they read as plain words.
_JOINED = re.compile(r"\b(lower|upper)(?=[a-z]{3,})")
EPS = 1e-6  # file units: a joint this close to its parent is a connector, not a segment


def clean_words(label: str) -> str:
    """'left l thumb' -> 'left thumb', 'left left finger base' -> 'left finger base',
    'lowerneck' -> 'lower neck', 'left eye l' -> 'left eye': a side said once, no stray letters."""
    words = _JOINED.sub(r"\1 ", label.strip().lower()).split()
    side = words[0] if words and words[0] in SIDES else ""
    rest = [w for w in words[1 if side else 0 :] if w not in SIDES and w not in ("l", "r")]
    return " ".join([side, *rest]).strip() if rest else label.strip().lower()


def plain_labels(skeleton: Skeleton) -> dict[str, str]:
    """Every joint's anatomical name in plain words."""
    return {name: clean_words(label) for name, label in rig_table(skeleton).items()}


def _rank(skeleton: Skeleton, named: set[int], index: int) -> tuple[int, int, int]:
    """Lower is better: the part the rig's structure names, then a real segment, then file order."""
    length = float(np.linalg.norm(np.asarray(skeleton.offsets)[index]))
    is_connector = index > 0 and length < EPS
    return (0 if index in named else 1, 1 if is_connector else 0, index)


def representatives(skeleton: Skeleton) -> dict[str, str]:
    """Joint name -> the joint offered for its body part (itself for most joints)."""
    labels = plain_labels(skeleton)
    named = {p for p in identify(skeleton).values() if p < len(skeleton.names)}
    groups: dict[str, list[int]] = {}
    for index, name in enumerate(skeleton.names):
        groups.setdefault(labels[name], []).append(index)
    chosen = {}
    for members in groups.values():
        best = min(members, key=lambda i: _rank(skeleton, named, i))
        for index in members:
            chosen[skeleton.names[index]] = skeleton.names[best]
    return chosen


def offered(skeleton: Skeleton, order: Iterable[str]) -> list[str]:
    """The joints of ``order`` that stand for their body part, each body part once, in order."""
    chosen = representatives(skeleton)
    seen: list[str] = []
    for name in order:
        if chosen.get(name) == name and name not in seen:
            seen.append(name)
    return seen


def ticked(skeleton: Skeleton, stored: Iterable[str]) -> list[str]:
    """Stored joints shown as ticks of the body parts they belong to (an older tick on a
    connector joint shows on its body part)."""
    chosen = representatives(skeleton)
    return sorted({chosen[name] for name in stored if name in chosen})
