"""imageform.color."""

__all__: list[str] = []
