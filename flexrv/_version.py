"""flexrv's version: the one place it is written (pyproject reads it; caches key on it)."""

__version__ = "0.1.0"
