#!/bin/bash
# Paper 000's GNN on a GPU in one command: `small` generated (unless already there), trained,
# evaluated on the test and validation splits, one test sample predicted. Figures go to $OUT.
#   OUT=/tmp/out bash benchmarks/gnn_gpu_run.sh [CONFIG]
set -o pipefail
OUT=${OUT:-/tmp/gnn-out}; STORE=${STORE:-/tmp/small.zarr}; RUN=${RUN:-/tmp/runs/gnn}
CONFIG=${1:-benchmarks/configs/gnn_small.yaml}
mkdir -p "$OUT"
if ! python -m datagen.cli validate "$STORE" > /dev/null 2>&1; then
  python -m datagen.cli generate --preset small --out "$STORE" --device cuda > "$OUT/generate.log" 2>&1
fi
python -m datagen.cli info "$STORE" > "$OUT/info.txt" 2>&1
python -m datagen.cli train gnn --data "$STORE" --out "$RUN" --config "$CONFIG" --device cuda --force > "$OUT/train.log" 2>&1
cp -r "$RUN/logs" "$RUN/run.json" "$OUT/"; cp "$RUN/train_summary.json" "$OUT/" 2>/dev/null
python -m datagen.cli evaluate "$RUN" --split test --json "$OUT/eval_test.json" --device cuda > "$OUT/eval_test.log" 2>&1
python -m datagen.cli evaluate "$RUN" --split val --max-frames 60 --json "$OUT/eval_val.json" --device cuda > "$OUT/eval_val.log" 2>&1
SAMPLE=$(python -c "from datagen.store import open_store; s=open_store('$STORE'); print(int(s.split('test', include_failed=False)[0]))")
python -m datagen.cli predict "$RUN" --data "$STORE" --sample "$SAMPLE" --out "$OUT/pred.usd" > "$OUT/predict.log" 2>&1
python -c "
from training.loop import read_metrics
for k in ('train/loss_epoch', 'val/coarse_mm', 'val/detail_mm'):
    print(k, {e: round(v, 3) for e, v in read_metrics('$RUN', k).items()})" | tee "$OUT/curves.txt"
grep -v "^Module\|^loaded" "$OUT/generate.log" 2>/dev/null | tail -4
tail -2 "$OUT/train.log"; grep -v "^Module\|^loaded\|^Warp\|^ \|CUDA" "$OUT/eval_test.log" "$OUT/eval_val.log" "$OUT/predict.log" | tail -24
