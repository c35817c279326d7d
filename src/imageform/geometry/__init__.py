"""imageform.geometry — camera geometry."""

__all__: list[str] = []
