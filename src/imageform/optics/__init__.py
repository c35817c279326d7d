"""imageform.optics."""

__all__: list[str] = []
