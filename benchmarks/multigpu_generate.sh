#!/bin/bash
# `drape generate` across the GPUs of one host (Ray, one task per GPU) against the same preset on
# one GPU of the same host, and the stores compared array by array. Figures go to $OUT.
#   OUT=/tmp/out PRESET=small [BATCH=28] bash benchmarks/multigpu_generate.sh [local|localN|ray1|rayN|compare A B]...
# local: the local executor on GPU 0 -> /tmp/local1.zarr; localN: the local executor on every GPU
# (--device cuda:0,cuda:1,..., no Ray) -> /tmp/localN.zarr; ray1: Ray restricted to GPU 0 ->
# /tmp/ray1.zarr; rayN: Ray on every GPU -> /tmp/rayN.zarr (N the GPU count). BATCH sets
# simulation.batch_size (the store does not depend on it): with BATCH = scenes / N, one GPU runs N
# batches one after another and N GPUs one each, which is the scaling a preset larger than one
# batch sees. NVLink multicast stays off (this host's rule).
set -o pipefail
export NCCL_NVLS_ENABLE=0 TORCH_SYMM_MEM_DISABLE_MULTICAST=1 NVSHMEM_DISABLE_NVLS=1
OUT=${OUT:-/tmp/mg-out}; PRESET=${PRESET:-small}; mkdir -p "$OUT"
NGPU=$(python -c "import torch; print(torch.cuda.device_count())")
nvidia-smi --query-gpu=index,name,memory.total --format=csv > "$OUT/gpus.txt"
CFG=/tmp/$PRESET-config.yaml
python -m datagen.cli generate --preset "$PRESET" --out /tmp/unused --print-config > "$CFG.json"
python -c "
import json, sys; c = json.load(open('$CFG.json'))
if '${BATCH:-}': c['simulation']['batch_size'] = int('${BATCH:-0}')
json.dump(c, open('$CFG', 'w'))"
run() {  # name, extra env, extra args
  local name=$1; shift
  env "$@" python -m datagen.cli generate "$CFG" --out /tmp/$name.zarr --device cuda $EXTRA > "$OUT/generate_$name.log" 2>&1
  echo "== $name"; grep -E "ray task|process [0-9]|end to end|simulator alone|simulated|valid|rror" "$OUT/generate_$name.log" | tail -6
}
while [ $# -gt 0 ]; do
  case $1 in
    local) EXTRA="" run local1 CUDA_VISIBLE_DEVICES=0 ;;
    ray1) EXTRA="--executor ray" run ray1 CUDA_VISIBLE_DEVICES=0 ;;
    rayN) EXTRA="--executor ray" run ray$NGPU ;;
    localN) EXTRA="--device $(python -c "print(','.join(f'cuda:{i}' for i in range($NGPU)))")" run local$NGPU ;;
    compare) python benchmarks/compare_stores.py /tmp/$2.zarr /tmp/$3.zarr --json "$OUT/compare_$2_$3.json" \
               > "$OUT/compare_$2_$3.txt" 2>&1; echo "== compare $2 $3"; tail -3 "$OUT/compare_$2_$3.txt"; shift 2 ;;
  esac
  shift
done
