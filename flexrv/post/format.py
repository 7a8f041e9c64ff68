"""Number formatting for tables and summaries (CLI tables, workflow summaries):
one rule everywhere.

>>> fmt(6214726455202.804), fmt(17138.2), fmt(0.123456), fmt([1, 2.5]), fmt(None)
('6.215e+12', '17138', '0.1235', '1, 2.5', '–')
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np


def fmt(value: Any) -> str:
    """A table cell: floats (numpy included) with 4 significant figures below 1000, whole
    numbers from 1000 to 1e5, exponent notation outside 1e-3 .. 1e5 (never
    ``6214726455202.804``), lists element-wise."""
    if value is None:
        return "–"
    if isinstance(value, (bool, np.bool_)):
        return str(bool(value))
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        v = float(value)
        if not math.isfinite(v):
            return str(v)
        if v == 0:
            return "0"
        if 1e3 <= abs(v) < 1e5:
            return f"{v:.0f}"  # whole units: 17138, not 1.714e+04
        if 1e-3 <= abs(v) < 1e3:
            return f"{v:.4g}"
        return f"{v:.3e}"
    if isinstance(value, (list, tuple)):
        return ", ".join(fmt(v) for v in value)
    return str(value)
