"""Fused CUDA kernels (numba's CUDA target) for arrays on a GPU (issue 29).

Private: the public functions dispatch here when their input is a CUDA array (a PyTorch CUDA
tensor or a CuPy array, through ``__cuda_array_interface__``) and numba's CUDA target is
available. Importing this package imports nothing; each module imports ``numba.cuda`` when
first used, so ``import imageform`` never touches the GPU.
"""
