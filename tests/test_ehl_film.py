"""Closed-form EHL film formulas (flexrv.ehl.film).

Cross-checks between independent published fits: Hamrock & Dowson (1977) and
Moes / Nijenbanning–Venner–Moes (1994) were fitted by different groups to different
numerical data, so agreement within their stated scatter (~10-15 %) in the
piezoviscous-elastic regime tests both coefficient sets.
"""

import numpy as np
import pytest

from flexrv.ehl.film import dimensionless_groups, ellipticity_approx, hamrock_dowson, moes_central, pan_hamrock_line
from flexrv.contact.hertz import point_contact
from flexrv.errors import InputError

E = 2.2e11
ETA, ALPHA = 0.05, 2e-8


@pytest.mark.parametrize("load,speed,ry", [(100.0, 1.0, 0.01), (1000.0, 1.0, 0.01), (100.0, 1.0, 0.04),
                                           (500.0, 1.0, 0.1), (50.0, 0.1, 0.01)])
def test_hamrock_dowson_vs_moes_piezoviscous_elastic(load, speed, ry):
    """HD and Moes h_c agree within 15 % for M = 100-3000, L = 6-12, lambda = 0.1-1."""
    g = dimensionless_groups(load, speed, 0.01, ry, E, ETA, ALPHA)
    assert 100 <= g.moes_m <= 3000 and 5 <= g.moes_l <= 15
    hc, hmin = hamrock_dowson(load, speed, 0.01, ry, E, ETA, ALPHA)
    assert abs(moes_central(load, speed, 0.01, ry, E, ETA, ALPHA) / hc - 1.0) < 0.15
    assert 0.4 * hc < hmin < hc  # minimum film below the central film


def test_hamrock_dowson_power_laws_and_vectorised():
    """h_c ~ u^0.67 Q^-0.067 eta0^0.67 alpha^0.53 exactly (Hamrock & Dowson 1977)."""
    q = np.array([10.0, 100.0, 1000.0])
    u = np.array([0.1, 1.0, 10.0])
    hc, _ = hamrock_dowson(q[:, None], u[None, :], 0.01, 0.03, E, ETA, ALPHA)
    assert hc.shape == (3, 3)
    np.testing.assert_allclose(hc[1, :] / hc[0, :], 10.0**-0.067, rtol=1e-12)
    np.testing.assert_allclose(hc[:, 1] / hc[:, 0], 10.0**0.67, rtol=1e-12)
    h2, _ = hamrock_dowson(100.0, 1.0, 0.01, 0.03, E, 2 * ETA, 2 * ALPHA)
    np.testing.assert_allclose(h2 / hc[1, 1], 2.0**0.67 * 2.0**0.53, rtol=1e-12)


def test_ellipticity_fit_matches_exact():
    """k = 1.0339 (ry/rx)^0.636 within 3.4 % of the exact Hertz ellipticity for ry/rx = 1-30
    (Hamrock & Brewe 1983)."""
    ratio = np.array([1.0, 2.0, 5.0, 10.0, 30.0])
    exact = point_contact(100.0, 0.01, 0.01 * ratio, E).ellipticity
    assert np.max(np.abs(ellipticity_approx(0.01, 0.01 * ratio) / exact - 1.0)) < 0.035


def test_pan_hamrock_line_scaling():
    """Line contact: h_c ~ (w/L)^-0.166 u^0.692 (Pan & Hamrock 1989); 1 m/s, 1 kN over 10 mm
    of R = 10 mm steel gives a film in the 0.1-1 um range."""
    hc, hmin = pan_hamrock_line(1000.0, 0.01, 1.0, 0.01, E, ETA, ALPHA)
    assert 1e-7 < hc < 1e-6 and 0.3 * hc < hmin < 1.5 * hc
    hc2, _ = pan_hamrock_line(2000.0, 0.02, 2.0, 0.01, E, ETA, ALPHA)  # same w/L
    np.testing.assert_allclose(hc2 / hc, 2.0**0.692, rtol=1e-12)


@pytest.mark.parametrize("bad", [dict(load=0.0), dict(speed=-1.0), dict(rx=0.0), dict(pressure_viscosity=0.0)])
def test_bad_input(bad):
    args = dict(load=100.0, speed=1.0, rx=0.01, ry=0.02, e_eff=E, viscosity=ETA, pressure_viscosity=ALPHA)
    args.update(bad)
    with pytest.raises(InputError, match=next(iter(bad))):
        hamrock_dowson(**args)
