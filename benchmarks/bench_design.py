"""Benchmark: analytic design report and pin load distribution.

Run: python benchmarks/bench_design.py
Prints wall-clock figures (median of repeated runs) for
* design_report(preset) for rv221 and rv40e,
* one pin load distribution (40 pins, Palmgren law) and one pin_gap call,
* one main-bearing ball load solve.
"""

from __future__ import annotations

import statistics
import time


def _time(fn, repeat: int = 7) -> tuple[float, float]:
    fn()  # warm-up (imports, caches)
    runs = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        runs.append(time.perf_counter() - t0)
    return statistics.median(runs), min(runs)


def main() -> None:
    from flexrv.analysis.bearing_load import ball_load_distribution
    from flexrv.analysis.pin_load import reducer_pin_loads
    from flexrv.analysis.report import design_report
    from flexrv.contact.hertz import effective_modulus
    from flexrv.design import load
    from flexrv.geometry.bearing import BallBearingGeometry
    from flexrv.geometry.cycloid import nominal_disc_pose, pin_gap, pin_positions, to_disc_frame

    rows = []
    for name in ("rv221", "rv40e"):
        r = load(name)
        med, best = _time(lambda: design_report(r), repeat=5)
        rows.append((f"design_report({name})", med, best))
        med, best = _time(lambda: reducer_pin_loads(r, r.operating.rated_torque_Nm), repeat=50)
        rows.append((f"pin load distribution {name} ({r.second_stage.pin_count} pins)", med, best))
    r = load("rv40e")
    ss = r.second_stage
    c, rot = nominal_disc_pose(ss.pin_count, ss.eccentricity, 0.3)
    pins = to_disc_frame(pin_positions(ss.pin_count, ss.pin_circle_radius), c, rot)
    med, best = _time(
        lambda: pin_gap(pins, ss.pin_count, ss.pin_circle_radius, ss.pin_radius, ss.eccentricity, d_pin_radius=5e-6),
        repeat=200,
    )
    rows.append(("pin_gap, 40 pins, cold start", med, best))
    _, _, phi = pin_gap(pins, ss.pin_count, ss.pin_circle_radius, ss.pin_radius, ss.eccentricity)
    med, best = _time(
        lambda: pin_gap(
            pins, ss.pin_count, ss.pin_circle_radius, ss.pin_radius, ss.eccentricity, d_pin_radius=5e-6, phi0=phi
        ),
        repeat=200,
    )
    rows.append(("pin_gap, 40 pins, warm start", med, best))
    g = BallBearingGeometry.from_design(load("rv221").main_bearing)
    e = float(effective_modulus(208e9, 0.3, 208e9, 0.3))
    med, best = _time(lambda: ball_load_distribution(g, e, force=(20e3, 0, 15e3), moment=(0, 5e3)), repeat=20)
    rows.append(("ball load distribution rv221 (2 x 26 balls, 5 DOF)", med, best))
    width = max(len(n) for n, *_ in rows)
    print(f"{'benchmark':<{width}}  median [ms]  best [ms]")
    for name, med, best in rows:
        print(f"{name:<{width}}  {med * 1e3:11.3f}  {best * 1e3:9.3f}")


if __name__ == "__main__":
    main()
