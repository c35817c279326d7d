"""imageform._kernels."""

__all__: list[str] = []
