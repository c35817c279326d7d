"""imageform._cuda: fused CUDA kernels (numba's CUDA target) for CUDA arrays of any library.

Private; the public functions dispatch here when their input is a CUDA array
(docs/design.md, "GPU kernels"). Modules import numba's CUDA target on first use only.
"""

__all__: list[str] = []
