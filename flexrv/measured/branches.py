"""Branches of a torque-angle loop: the monotone runs of the torque between its turning points.

A bench torque carries noise, so a turning point counts only when the torque moves
back from it by more than ``hysteresis`` of the loop's torque range (default 5 %):
a wiggle of a few N m on a 412 N m loop does not split a branch.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Branch:
    """Rows ``start .. stop`` (inclusive) over which the torque rises (``direction`` +1) or falls (-1)."""

    start: int
    stop: int
    direction: int


def turning_points(torque, hysteresis: float = 0.05) -> list[int]:
    """Indices of the torque's turning points (extrema confirmed by a reversal larger than
    ``hysteresis`` x the torque range), first and last sample included."""
    t = np.asarray(torque, dtype=float)
    n = len(t)
    if n < 2:
        return list(range(n))
    band = hysteresis * float(t.max() - t.min())
    points = [0]
    direction = 0
    ext = 0  # index of the running extremum of the current run
    for i in range(1, n):
        if direction == 0:
            if abs(t[i] - t[0]) > band:
                direction, ext = (1 if t[i] > t[0] else -1), i
        elif direction * (t[i] - t[ext]) >= 0:
            ext = i
        elif direction * (t[ext] - t[i]) > band:
            points.append(ext)
            direction, ext = -direction, i
    if points[-1] != n - 1:
        points.append(n - 1)
    return points


def loop_branches(torque, hysteresis: float = 0.05) -> list[Branch]:
    """The loop's branches between consecutive turning points (:func:`turning_points`);
    a run whose torque changes by less than the hysteresis band is dropped."""
    t = np.asarray(torque, dtype=float)
    tp = turning_points(t, hysteresis)
    band = hysteresis * float(t.max() - t.min()) if len(t) else 0.0
    out = []
    for a, b in zip(tp[:-1], tp[1:]):
        d = t[b] - t[a]
        if abs(d) > band:
            out.append(Branch(int(a), int(b), 1 if d > 0 else -1))
    return out
