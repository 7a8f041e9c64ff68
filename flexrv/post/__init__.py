"""Post-processing: the Results object (xarray), save/load, TE, spectra, statistics.

``flexrv.post.Results`` is imported on first access: the package's light modules (number
formats, definitions) do not import xarray."""


def __getattr__(name: str):
    if name == "Results":
        from flexrv.post.results import Results

        return Results
    raise AttributeError(f"module 'flexrv.post' has no attribute {name!r}")
