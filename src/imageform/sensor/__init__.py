"""imageform.sensor."""

__all__: list[str] = []
