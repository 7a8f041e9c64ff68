"""Post-processing: the Results object (xarray), save/load, TE, spectra, statistics."""

from flexrv.post.results import Results  # noqa: F401
