#!/usr/bin/env bash
# One lent GPU's whole check for issue 29, as one command (the device's budget is 15 minutes:
# start, this script, transfers). Run from the repository root on the lent machine:
#
#     bash benchmarks/gpu_lease.sh            # results under $OUT (default ./gpu-out)
#
# Python packages the machine's image lacks travel as wheels in .whl/ (imageform's
# array-api-compat and imagecodecs, kornia and kornia_rs for the peer rows, dask and
# distributed for `batch`); they are installed into /tmp/site, never over the image's own.
# `bash benchmarks/gpu_wheels.sh` builds .whl/ here first (a fresh checkout has none).
# Steps, each under its own time limit so that a stuck one costs its step, not the lease:
#   1. env.txt: the device, driver, library versions, whether imageform's CUDA kernels run;
#   2. the timing table, benchmarks/bench_gpu.py (gpu-<device>-<date>.md; progress rows in
#      bench-progress.log as they are measured);
#   3. host-profile.txt: the host's time per call, one row per fused call with its cProfile
#      (benchmarks/profile_gpu_host.py), and host-profile-dry.txt: the same with --dry (no
#      device: a stub launch) on this machine's CPU, for comparison with the CPU-only runs;
#   4. the device tests (tests.log): the backend matrix on torch CUDA and CuPy, the
#      pointwise set under set_sync_debug_mode("error"), the geometry/demosaic kernels, the
#      --device cuda commands, the meta-device matrix.
# One `run` call may last 600 s and the step limits add up to 720 s (bench 300, host 150 + 60,
# tests 210): STEPS picks steps for one call, e.g. STEPS=env,bench then STEPS=env,host,tests
# (default: all four; env is cheap and installs the wheels, so give it in every call).
set -u
STEPS=${STEPS:-env,bench,host,tests}
want() { case ",$STEPS," in *",$1,"*) return 0 ;; *) return 1 ;; esac; }
OUT=${OUT:-gpu-out}
mkdir -p "$OUT"
export PYTHONUNBUFFERED=1 OPENBLAS_NUM_THREADS=1
if compgen -G ".whl/*.whl" >/dev/null; then
  python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade \
    --target /tmp/site .whl/*.whl || echo "wheel install failed" >&2
  export PYTHONPATH=/tmp/site
fi
export PYTHONPATH="src:.:${PYTHONPATH:-}"
STAMP=$(date -u +%Y-%m-%d)

status() { timeout 120 python3 -c "from imageform._cuda import _launch; import numpy as np, torch
x = torch.rand(8, 8, 3, device='cuda', dtype=torch.float64)
from imageform import color as c
c.convert(x, 'srgb', 'lab'); torch.cuda.synchronize()
print('imageform CUDA kernels:', _launch.status())" 2>&1 | tail -3; }

{
  date -u
  nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.sm,clocks.max.mem --format=csv
  python3 -c "import sys, numpy, numba, torch, cupy; print(sys.version.split()[0], 'numpy', numpy.__version__, 'numba', numba.__version__, 'torch', torch.__version__, 'cupy', cupy.__version__)"
  python3 -m pip show numba-cuda kornia 2>/dev/null | grep -E "^(Name|Version)"
  S=$(status); echo "$S"
  if echo "$S" | grep -q "kernels: off" && [ -d /usr/local/cuda ]; then
    export CUDA_HOME=/usr/local/cuda
    echo "retry with CUDA_HOME=$CUDA_HOME"; status
  fi
} 2>&1 | tee "$OUT/env.txt"
grep -q "^retry with CUDA_HOME" "$OUT/env.txt" && export CUDA_HOME=/usr/local/cuda

DEV=$(nvidia-smi --query-gpu=name --format=csv,noheader | head -1 | tr -cd 'A-Za-z0-9' | tr A-Z a-z | sed 's/^nvidia//')
if want bench; then
timeout "${BENCH_S:-300}" python3 benchmarks/bench_gpu.py --device cuda \
  --note "One run on a lent machine (benchmarks/gpu_lease.sh): $(tail -1 "$OUT/env.txt")." \
  --out "$OUT/gpu-${DEV:-gpu}-$STAMP.md" 2>"$OUT/bench-progress.log" >/dev/null
echo "bench exit $?" | tee -a "$OUT/bench-progress.log"
fi

# host time per call on the device (every row's first call compiles its kernel), then the
# same calls --dry on this machine's CPU (stub launch), to relate the two measurements
if want host; then
timeout "${HOST_S:-150}" python3 benchmarks/profile_gpu_host.py >"$OUT/host-profile.txt" 2>&1
echo "host profile exit $?" >>"$OUT/host-profile.txt"
grep -E "^(\| |imageform|fast launch|host profile)" "$OUT/host-profile.txt" | head -30
timeout 60 python3 benchmarks/profile_gpu_host.py --dry --top 10 >"$OUT/host-profile-dry.txt" 2>&1
fi

want tests || exit 0
timeout "${TESTS_S:-210}" python3 -m pytest -q -n 8 -p no:cacheprovider -rfEs \
  tests/backends/test_cuda_device.py tests/backends/test_cuda_geometry_device.py \
  tests/backends/test_cuda_cli_device.py tests/backends/test_meta_device.py \
  >"$OUT/tests.log" 2>&1
echo "tests exit $?" >>"$OUT/tests.log"
grep -E "^(FAILED|ERROR|SKIPPED)" "$OUT/tests.log" | head -40
tail -3 "$OUT/tests.log"
