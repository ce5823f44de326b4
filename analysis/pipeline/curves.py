"""The clinical angles frame by frame, kept with the playback arrays for the recording page's
chart: the very series the result's ``clinical_angles`` (the table beside the chart) are the
ranges of, so the chart and the table show the same numbers (`webapp.reports.playback`)."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from analysis.clinical import Measured

CURVE_PREFIX = "clinical_angle__"  # + an angle name of `analysis.clinical.ANGLE_NAMES`


def angle_curves(measured: Measured) -> dict[str, npt.NDArray[np.float32]]:
    """{CURVE_PREFIX + angle name: degrees per frame (NaN where not measured)}, float32."""
    return {
        CURVE_PREFIX + name: np.asarray(values, dtype=np.float32)
        for name, values in measured.series.items()
    }


def curve_name(key: str) -> str | None:
    """The angle name of an arrays key, None for the other arrays."""
    return key[len(CURVE_PREFIX) :] if key.startswith(CURVE_PREFIX) else None
