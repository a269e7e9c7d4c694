# Shared set-up of the device-machine scripts (sourced by scripts/gpu_train.sh, scripts/gpu_clean_stride.sh and
# scripts/gpu_detected.sh, from
# the repository root): installs the wheels carried in .gpu/whl (pure-Python dependencies missing there), puts the
# repository on PYTHONPATH, makes this run's folder R=runs/gpu/<UTC time> and OUT, writes R/env.txt (GPU, CPUs,
# torch) and starts `nvidia-smi dmon` into R/dmon.txt (its pid in DMON; empty without nvidia-smi).
if compgen -G ".gpu/whl/*.whl" > /dev/null; then
  python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --target /tmp/site .gpu/whl/*.whl \
    && export PYTHONPATH=/tmp/site
fi
export PYTHONUNBUFFERED=1 PYTHONPATH=$PWD:${PYTHONPATH:-}
STAMP=$(date -u +%Y%m%d-%H%M%S); R=runs/gpu/$STAMP
mkdir -p "$R" "$OUT"
{
  command -v nvidia-smi > /dev/null && nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv
  echo "cpus $(nproc)"; grep -m 1 "model name" /proc/cpuinfo
  python3 -c "import torch, numpy; print('torch', torch.__version__, 'cuda', torch.cuda.is_available(), 'numpy', numpy.__version__)"
} > "$R/env.txt" 2>&1
cat "$R/env.txt"
DMON=
if command -v nvidia-smi > /dev/null; then nvidia-smi dmon -s um -d 10 > "$R/dmon.txt" 2>&1 & DMON=$!; fi
