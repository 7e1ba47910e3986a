#!/bin/bash
# Issue 24 on ONE GPU in two commands of at most ten minutes, the machine kept warm between them:
# paper 000's GNN on `medium` (the store made, the full model trained with seeds 0 and 1 side by side),
# then the runs resumed and both evaluated on every test frame (Tables 1 and 2).
#   OUT=$OUT PART=1 bash benchmarks/gnn_one_gpu_run.sh   # the store, then training (~9.5 min)
#   OUT=$OUT PART=2 bash benchmarks/gnn_one_gpu_run.sh   # training resumed, then the evaluations (~9.5 min)
# The logs come back as $OUT/part$PART.tgz (the device tool returns at most eight files) and the runs'
# best weights as $OUT/run_full-s*.tgz; PART=1 also packs warp's kernel cache (warpcache.tgz), so that
# the next machine of the same card need not compile the simulator's kernels.
set -o pipefail
OUT=${OUT:?}; PART=${PART:?}; W=$OUT/work; mkdir -p "$W"
common=(GEN_DEVICES=cuda:0 NO_TESTS=1 RUNS=/tmp/runs OMP_NUM_THREADS=6 BUDGET=${BUDGET:-565}
        RUNLIST="full-s0:full:0:0 full-s1:full:1:0" OUT="$W")
if [ "$PART" = 1 ]; then
  env "${common[@]}" NO_EVAL=1 bash benchmarks/gnn_medium_gpu_run.sh > "$OUT/part1.log" 2>&1
  tar czf "$OUT/warpcache.tgz" -C "$HOME/.cache" warp 2>/dev/null
else
  env "${common[@]}" MORE=1 EVAL_SECONDS=${EVAL_SECONDS:-270} bash benchmarks/gnn_medium_gpu_run.sh > "$OUT/part2.log" 2>&1
  mv "$W"/run_full-s*.tgz "$OUT/" 2>/dev/null
fi
grep -v "^Module\|^Warp\|^   " "$OUT/part$PART.log" | tail -60
tar czf "$OUT/part$PART.tgz" --exclude='*.ckpt' --exclude='events.out.*' --exclude='medium_run.tgz' -C "$W" . && rm -rf "$W"
ls -la "$OUT"
