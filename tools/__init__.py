"""Development tools of hht3d (not part of the package): run from the repository root as ``python -m tools.NAME``."""
