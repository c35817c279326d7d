"""imageform.spectral."""

__all__: list[str] = []
