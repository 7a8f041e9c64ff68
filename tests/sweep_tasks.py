"""Tasks used by the sweep tests (importable by dask workers via PYTHONPATH)."""

import time


def slow_ratio(reducer, delay: float = 0.0, fail_above: float | None = None) -> dict:
    """Total ratio of the design (closed form) after sleeping ``delay`` s; raises for
    eccentricities above ``fail_above`` to exercise failure recording."""
    time.sleep(delay)
    fs, ss = reducer.first_stage, reducer.second_stage
    if fail_above is not None and ss.eccentricity_mm > fail_above:
        raise RuntimeError(f"eccentricity {ss.eccentricity_mm} above {fail_above}")
    ratio = 1 + fs.planet_teeth * ss.pin_count / (fs.sun_teeth * (ss.pin_count - ss.disc_teeth))
    return {"kinematics": {"ratio": ratio}, "k1": ss.shortening_coefficient}
