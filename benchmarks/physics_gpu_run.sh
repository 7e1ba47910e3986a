#!/bin/bash
# The physics issue's GPU figures in one command: the six 300-frame runs (T-shirt, dress, pants x
# walk, dance_disco) at the production settings, with and without the untangling, then `small`
# generated and its recorded garments' strain per material. Logs go to $OUT.
#   OUT=/tmp/out PHASE=six|small bash benchmarks/physics_gpu_run.sh
set -o pipefail
OUT=${OUT:-/tmp/physics-out}; PHASE=${PHASE:-six}
mkdir -p "$OUT"
filter() { grep -v "^Module\|^Warp\|^   \|CUDA Toolkit\|Devices:\|Kernel cache"; }
if [ "$PHASE" = six ]; then
  python benchmarks/bench_sim.py run-scenes --inputs .simbench/runs.pkl --device cuda --out-dir "$OUT/six" 2>&1 \
    | filter | tee "$OUT/six_runs.txt"
  python benchmarks/bench_sim.py run-scenes --inputs .simbench/runs.pkl --device cuda --set untangle_step=0 2>&1 | filter | tee "$OUT/six_runs_untangle_off.txt"
fi
if [ "$PHASE" = small ]; then
  ( time python -m datagen.cli generate --preset small --out /tmp/small.zarr --device cuda ) > "$OUT/generate_small.txt" 2>&1
  filter < "$OUT/generate_small.txt" | tail -n 12
  python -m datagen.cli validate /tmp/small.zarr | tee -a "$OUT/generate_small.txt"
  python benchmarks/garment_strain.py /tmp/small.zarr 2>&1 | filter | tee "$OUT/small_strain.txt"
fi
