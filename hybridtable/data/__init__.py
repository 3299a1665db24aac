"""Data files shipped with the package (the paper's tables)."""

__all__: list[str] = []
