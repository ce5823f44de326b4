"""A prescription's dosage in the words patients and therapists read on its pages."""

from __future__ import annotations

from typing import Protocol

DAY_NAMES = ("Monday", "Tuesday", "Wednesday", "Thursday", "Friday", "Saturday", "Sunday")


class Dosage(Protocol):
    sets: int | None
    target_repetitions: int | None
    hold_seconds: int | None
    sessions_per_week: int | None

    @property
    def weekdays(self) -> list[int]: ...


def counted(n: int, word: str) -> str:
    return f"{n} {word if n == 1 else word + 's'}"


def listed(words: list[str]) -> str:
    return words[0] if len(words) == 1 else ", ".join(words[:-1]) + " and " + words[-1]


def amount(dosage: Dosage) -> str:
    """ "3 sets of 10 repetitions", "10 repetitions", "2 sets" or ""."""
    sets, reps = dosage.sets, dosage.target_repetitions
    if sets and reps:
        return f"{counted(sets, 'set')} of {counted(reps, 'repetition')}"
    if reps:
        return counted(reps, "repetition")
    return counted(sets, "set") if sets else ""


def dosage_words(dosage: Dosage) -> str:
    """ "3 sets of 10 repetitions, holding each for 5 seconds, 3 sessions a week (Monday,
    Wednesday and Friday)"; "No dosage set" when the therapist gave none."""
    parts = [amount(dosage)]
    if dosage.hold_seconds:
        parts.append(f"holding each for {counted(dosage.hold_seconds, 'second')}")
    if dosage.sessions_per_week:
        parts.append(f"{counted(dosage.sessions_per_week, 'session')} a week")
    text = ", ".join(part for part in parts if part)
    if dosage.weekdays:
        days = listed([DAY_NAMES[day] for day in dosage.weekdays])
        text = f"{text} (on {days})" if text else f"On {days}"
    return text[:1].upper() + text[1:] if text else "No dosage set"
