"""Post-processing: the Results object (xarray), save/load, TE, spectra, statistics."""

from flexrv.post.results import ARCSEC, Results  # noqa: F401
