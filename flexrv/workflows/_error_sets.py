"""Example manufacturing-error sets drawn from ISO tolerance grades (one sample reducer each).

``python -m flexrv.workflows._error_sets`` (re)writes ``flexrv/design/presets/errors/iso_grade5_<preset>.toml``
for rv40e and rv221. Every deviation is drawn ONCE, uniformly within its tolerance zone, from
``numpy.random.default_rng(seed)``; the tolerance of each field is derived from the design's
geometry with the standard formulas below and written beside it in the file. Nothing is tuned to
a transmission-error target.

Sources and assumptions:

* ISO 286-1 standard tolerance IT5 by nominal size (table below) for sizes: pin diameter, the
  eccentric journal (taken as the positional zone of the eccentric axis).
* ISO 1328-1:1995 accuracy grade 5 base formulas (step sqrt(2) per grade) with module m and
  reference diameter d [mm]: single pitch f_pt = 0.3 (m + 0.4 sqrt d) + 4, cumulative pitch
  F_p = 0.3 m + 1.25 sqrt d + 7, profile form f_falpha = 2.5 sqrt m + 0.17 sqrt d + 0.5 [um];
  radial runout F_r = 0.8 F_p. The pin ring / disc teeth are treated as a gear of module
  m = 2 R_p / z_rp and d = 2 R_p.
* Assumption (no standard covers it): the pin grooves in the housing, the crank holes in the
  discs and the crank bores in the carrier are jig-ground to the same +-f_pt/2 positional class.
* Disc profile: order-1 harmonic = cumulative pitch error (amplitude within F_p/2), order-z_c
  harmonic = tooth-periodic form error (amplitude within f_falpha/2), random phases.
* First stage: radial runout within F_r/2 projected on the line of action (x sin alpha);
  planet assembly phase within +-f_pt/2 on the planet base radius.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

#: ISO 286-1 IT5 [um] by nominal size range (upper bound of the range [mm], IT5)
IT5_UM = (
    (3, 4),
    (6, 5),
    (10, 6),
    (18, 8),
    (30, 9),
    (50, 11),
    (80, 13),
    (120, 15),
    (180, 18),
    (250, 20),
    (315, 23),
    (400, 25),
    (500, 27),
)


def it5_um(size_mm: float) -> float:
    """ISO 286-1 IT5 [um] of a nominal size [mm] (1..500 mm)."""
    for upper, value in IT5_UM:
        if size_mm <= upper:
            return float(value)
    raise ValueError(f"size {size_mm} mm beyond the IT table")


def iso1328_grade5_um(m: float, d: float) -> dict[str, float]:
    """ISO 1328-1:1995 grade-5 limits [um] for module m and reference diameter d [mm]."""
    f_p = 0.3 * m + 1.25 * math.sqrt(d) + 7.0
    return {
        "f_pt": 0.3 * (m + 0.4 * math.sqrt(d)) + 4.0,
        "F_p": f_p,
        "f_falpha": 2.5 * math.sqrt(m) + 0.17 * math.sqrt(d) + 0.5,
        "F_r": 0.8 * f_p,
    }


def _fmt(a) -> str:
    return "[" + ", ".join(f"{float(v) + 0.0:g}" for v in np.ravel(a)) + "]"


def _fmt2(a) -> str:
    return "[" + ", ".join(_fmt(row) for row in a) + "]"


def iso_grade5_toml(preset: str, seed: int = 2026) -> str:
    """TOML text of one grade-5 sample error set for a preset (see the module docstring)."""
    from flexrv.design import load

    r = load(preset)
    fs, ss, cs = r.first_stage, r.second_stage, r.crankshaft
    z, n, nd, zc = ss.pin_count, fs.n_planets, ss.n_discs, ss.disc_teeth
    rng = np.random.default_rng(seed)

    def sym(half, size=None):
        return np.round(rng.uniform(-half, half, size), 2) + 0.0

    def amp(top):
        return round(float(rng.uniform(0.0, top)), 2), round(float(rng.uniform(0.0, 360.0)), 1)

    m_pin, d_pin = 2.0 * ss.pin_circle_radius_mm / z, 2.0 * ss.pin_circle_radius_mm
    g = iso1328_grade5_um(m_pin, d_pin)
    it_pin = it5_um(2.0 * ss.pin_radius_mm)
    it_ecc = it5_um(cs.eccentric_journal_diameter_mm)
    alpha = fs.pressure_angle
    g_sun = iso1328_grade5_um(fs.module_mm, fs.module_mm * fs.sun_teeth)
    g_pl = iso1328_grade5_um(fs.module_mm, fs.module_mm * fs.planet_teeth)
    rb_p_mm = 0.5 * fs.module_mm * fs.planet_teeth * math.cos(alpha)
    phase_pl = (g_pl["f_pt"] / 2 * 1e-3) / rb_p_mm * 180.0 / math.pi * 60.0
    ecc_phase = it_ecc / 2 * 1e-3 / ss.eccentricity_mm * 180.0 / math.pi * 60.0
    half_pt = g["f_pt"] / 2
    text = f"""# Example manufacturing and assembly error set for the {preset} preset (z_rp = {z}, N = {n} cranks,
# {nd} discs): ONE sample reducer, every deviation drawn once, uniformly within its tolerance zone
# (numpy.random.default_rng({seed}), rounded to 0.01 um / 0.01 arcmin / 0.1 deg). Nothing is tuned
# to any transmission-error target. Written by `python -m flexrv.workflows._error_sets` (sources and
# assumptions in its docstring). Load it with
#     flexrv.design.with_errors("{preset}", load_error_set("iso_grade5_{preset}"))
# ISO 1328-1:1995 grade 5 of the pin ring / disc teeth (m = 2 R_p / z_rp = {m_pin:.3g} mm, d = {d_pin:g} mm):
#   f_pt = {g["f_pt"]:.2f} um, F_p = {g["F_p"]:.2f} um, f_falpha = {g["f_falpha"]:.2f} um.

[errors.pins]
# ISO 286-1 IT5 pin rollers ({2 * ss.pin_radius_mm:g} mm): diameter within +-{it_pin / 2:g} um -> radius within +-{it_pin / 4:g} um
pin_radius_um = {_fmt(sym(it_pin / 4, z))}
# pin-groove positions within +-f_pt/2 = +-{half_pt:.2f} um, radial and tangential (assumption: jig-ground class)
pin_radial_position_um = {_fmt(sym(half_pt, z))}
pin_tangential_position_um = {_fmt(sym(half_pt, z))}
"""
    for k in range(nd):
        h1, hz = amp(g["F_p"] / 2), amp(g["f_falpha"] / 2)
        text += f"""
[[errors.discs]]
# disc {k}: order-1 harmonic = cumulative pitch error, amplitude within F_p/2 = {g["F_p"] / 2:.2f} um;
# order-z_c ({zc}) harmonic = tooth-periodic profile form error, amplitude within f_falpha/2 = {g["f_falpha"] / 2:.2f} um;
# crank-hole positions within +-f_pt/2 = +-{half_pt:.2f} um (assumption: jig-ground class)
harmonics = [{{ order = 1, amplitude_um = {h1[0]:g}, phase_deg = {h1[1]:g} }}, {{ order = {zc}, amplitude_um = {hz[0]:g}, phase_deg = {hz[1]:g} }}]
hole_radial_um = {_fmt(sym(half_pt, n))}
hole_tangential_um = {_fmt(sym(half_pt, n))}
"""
    ecc = sym(it_ecc / 2, (n, nd))
    phase = np.round(rng.uniform(-ecc_phase, ecc_phase, (n, nd)), 2) + 0.0
    text += f"""
[errors.cranks]
# eccentric axis position within the IT5 zone of the {cs.eccentric_journal_diameter_mm:g} mm eccentric journal ({it_ecc:g} um):
# +-{it_ecc / 2:g} um radial (eccentricity) and tangential, i.e. +-{it_ecc / 2:g} um / {ss.eccentricity_mm:g} mm = +-{ecc_phase:.2f} arcmin of phase
eccentricity_um = {_fmt2(ecc)}
eccentric_phase_arcmin = {_fmt2(phase)}
# crank bores in the carrier within +-f_pt/2 = +-{half_pt:.2f} um (assumption: jig-ground class)
bore_radial_um = {_fmt(sym(half_pt, n))}
bore_tangential_um = {_fmt(sym(half_pt, n))}
"""
    sun_top = g_sun["F_r"] / 2 * math.sin(alpha)
    pl_top = g_pl["F_r"] / 2 * math.sin(alpha)
    sun = amp(sun_top)
    pl_a = np.round(rng.uniform(0.0, pl_top, n), 2)
    pl_p = np.round(rng.uniform(0.0, 360.0, n), 1)
    text += f"""
[errors.first_stage]
# radial runout within F_r/2 (grade 5: sun F_r = {g_sun["F_r"]:.2f} um, planet F_r = {g_pl["F_r"]:.2f} um), projected on the
# line of action (x sin {fs.pressure_angle_deg:g} deg): sun within {sun_top:.2f} um, planets within {pl_top:.2f} um
sun_runout_um = {sun[0]:g}
sun_runout_phase_deg = {sun[1]:g}
planet_runout_um = {_fmt(pl_a)}
planet_runout_phase_deg = {_fmt(pl_p)}
# planet assembly phase on its crank: +-f_pt/2 of the planet ({g_pl["f_pt"]:.2f} um) on its base radius
# {rb_p_mm:.2f} mm -> +-{phase_pl:.2f} arcmin
planet_phase_arcmin = {_fmt(sym(phase_pl, n))}

[errors.clearances]
# the design's nominal needle clearance and preloaded crank supports: no extra clearance
needle_extra_clearance_um = 0.0
support_clearance_um = 0.0
"""
    return text


def main() -> None:
    folder = Path(__file__).resolve().parent.parent / "design" / "presets" / "errors"
    for preset in ("rv40e", "rv221"):
        path = folder / f"iso_grade5_{preset}.toml"
        path.write_text(iso_grade5_toml(preset))
        print(f"wrote {path}")


if __name__ == "__main__":
    main()
