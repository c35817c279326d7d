#!/usr/bin/env bash
# Build the ignored .whl/ folder that benchmarks/gpu_lease.sh installs on a lent GPU machine
# (that machine reaches no network; its image had Python 3.12, torch, CuPy and numba-cuda, but
# not these). Run here, on a machine with PyPI, before the device call:
#
#     bash benchmarks/gpu_wheels.sh            # then: run(..., carry=[".whl"])
#
# Binary wheels for CPython 3.12 on manylinux x86_64, without dependency resolution (`--no-deps`:
# kornia's torch dependency would pull a multi-GB CUDA build): the list names every package.
# NumPy is pinned to 2.4.x because numba-cuda 0.30.4 cannot compile a kernel on NumPy 2.5 (it
# registers np.row_stack, removed in 2.5; found on the H200 on 2026-11-28). About 40 MB, under
# the device tool's 64 MiB carry limit.
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PY:-3.12}
dest=.whl
rm -rf "$dest"
mkdir -p "$dest"
pkgs=(
  "numpy==2.4.6" "array-api-compat>=1.9" "imagecodecs>=2024.1" "tifffile>=2023.1"
  "kornia==0.9.0" "kornia_rs" "click>=8.1" "rich>=13" "markdown-it-py" "mdurl" "pygments"
  "dask>=2024.1" "distributed>=2024.1" "cloudpickle" "fsspec" "partd" "locket" "toolz"
  "pyyaml" "msgpack" "sortedcontainers" "tblib" "tornado" "zict" "psutil" "jinja2"
  "markupsafe" "packaging" "urllib3"
)
python3 -m pip download -q --no-deps --only-binary=:all: --implementation cp \
  --python-version "$PY" --platform manylinux_2_28_x86_64 --platform manylinux2014_x86_64 \
  --platform manylinux_2_17_x86_64 --platform any --dest "$dest" "${pkgs[@]}"
du -sh "$dest"
ls "$dest"
