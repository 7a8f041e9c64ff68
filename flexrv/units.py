"""The one place for unit constants (SI inside flexrv).

Each name says its direction: ``X_PER_Y`` is how many X make one Y, so a value
in Y times ``X_PER_Y`` is the value in X. Example: an angle in radians times
``ARCSEC_PER_RAD`` is the angle in arcseconds.

>>> round(1.0 * ARCSEC_PER_RAD)
206265
>>> round(600.0 * RAD_S_PER_RPM, 6)
62.831853
>>> 60.0 * RAD_PER_ARCSEC == RAD_PER_ARCMIN
True
"""

from __future__ import annotations

import math

#: radians per degree
RAD_PER_DEG = math.pi / 180.0
#: degrees per radian
DEG_PER_RAD = 180.0 / math.pi
#: radians per arcminute
RAD_PER_ARCMIN = math.pi / (180.0 * 60.0)
#: arcminutes per radian
ARCMIN_PER_RAD = 180.0 * 60.0 / math.pi
#: radians per arcsecond
RAD_PER_ARCSEC = math.pi / (180.0 * 3600.0)
#: arcseconds per radian
ARCSEC_PER_RAD = 180.0 * 3600.0 / math.pi
#: rad/s per revolution per minute
RAD_S_PER_RPM = 2.0 * math.pi / 60.0
#: revolutions per minute per rad/s
RPM_PER_RAD_S = 60.0 / (2.0 * math.pi)
#: metres per millimetre
M_PER_MM = 1e-3
#: metres per micrometre
M_PER_UM = 1e-6
#: micrometres per metre
UM_PER_M = 1e6
#: pascals per megapascal
PA_PER_MPA = 1e6
#: full turn [rad]
TWO_PI = 2.0 * math.pi
