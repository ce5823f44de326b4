"""How the API writes numbers and times: one datetime format (ISO 8601 in UTC, ending in `Z`,
whole seconds) and numbers rounded to what they can mean (a frame rate of 30.0003 is 30.0, a
score 0..100 to 0.1, angles to 0.1°, timings to 0.1 ms).

Rounding is by key, for the answers built as plain dicts (progress points, the results-page
data); a float the table does not name keeps four decimals (ratios such as a relative area). The
analysis result itself is served as the typed result's JSON, at the pipeline's precision
(`webapp.api.serializers.typed_json`).
"""

from __future__ import annotations

import datetime
from typing import Any

# Decimal places by key, wherever the key appears in a result.
PLACES = {
    "fps": 1,
    "score": 1,
    "pass_threshold": 1,
    "similarity": 1,  # degrees
    "alignment_tau": 3,
    "min": 1,  # clinical angles, degrees
    "max": 1,
    "range": 1,
    "duration_s": 2,
    "tempo": 2,
    "suggestion_distance": 3,
}
# Every value under these keys (a mapping of names to numbers).
PLACES_OF_VALUES = {"timings_ms": 1, "range_of_motion": 1, "gamma": 3}
DEFAULT_PLACES = 4


def rounded(value: Any, places: int = DEFAULT_PLACES) -> Any:
    """`value` with every float in it rounded (by key where PLACES names the key)."""
    if isinstance(value, float):
        return round(value, places)
    if isinstance(value, dict):
        return {key: _rounded_item(key, item) for key, item in value.items()}
    if isinstance(value, list | tuple):
        return [rounded(item, places) for item in value]
    return value


def _rounded_item(key: str, item: Any) -> Any:
    if key in PLACES_OF_VALUES and isinstance(item, dict):
        return {k: rounded(v, PLACES_OF_VALUES[key]) for k, v in item.items()}
    return rounded(item, PLACES.get(key, DEFAULT_PLACES))


def round_or_none(value: float | None, places: int) -> float | None:
    return None if value is None else round(float(value), places)


def utc_iso(value: datetime.datetime | str | None) -> str | None:
    """`2026-11-23T20:40:26Z`: UTC, whole seconds (a datetime, or an ISO string to normalise)."""
    if value is None:
        return None
    if isinstance(value, str):
        value = datetime.datetime.fromisoformat(value)
    if value.tzinfo is None:
        value = value.replace(tzinfo=datetime.UTC)
    utc = value.astimezone(datetime.UTC).replace(microsecond=0, tzinfo=None)
    return utc.isoformat() + "Z"
