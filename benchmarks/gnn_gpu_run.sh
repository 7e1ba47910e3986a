#!/bin/bash
# Paper 000's GNN on a GPU in one command: `small` generated (unless already there), trained,
# evaluated on the test and validation splits, one test sample predicted. Figures go to $OUT.
#   OUT=/tmp/out bash benchmarks/gnn_gpu_run.sh [CONFIG]
set -eo pipefail
OUT=${OUT:-/tmp/gnn-out}; STORE=${STORE:-/tmp/small.zarr}; RUN=${RUN:-/tmp/runs/gnn}
CONFIG=${1:-benchmarks/configs/gnn_small.yaml}
mkdir -p "$OUT"
if ! python -m datagen.cli validate "$STORE" > /dev/null 2>&1; then
  python -m datagen.cli generate --preset small --out "$STORE" --device cuda 2>&1 | grep -v "^Module\|^loaded" > "$OUT/generate.txt"
fi
python -m datagen.cli info "$STORE" > "$OUT/info.txt"
python -m datagen.cli train gnn --data "$STORE" --out "$RUN" --config "$CONFIG" --device cuda --force 2>&1 \
  | grep -v "^Module\|^loaded" > "$OUT/train.txt"
python -m datagen.cli evaluate "$RUN" --split test --json "$OUT/eval_test.json" --device cuda 2>&1 | grep -v "^Module\|^loaded" > "$OUT/eval_test.txt"
python -m datagen.cli evaluate "$RUN" --split val --json "$OUT/eval_val.json" --device cuda 2>&1 | grep -v "^Module\|^loaded" > "$OUT/eval_val.txt"
SAMPLE=$(python -c "from datagen.store import open_store; s=open_store('$STORE'); print(int(s.split('test', include_failed=False)[0]))")
python -m datagen.cli predict "$RUN" --data "$STORE" --sample "$SAMPLE" --out "$OUT/pred.usd" 2>&1 | tail -1 > "$OUT/predict.txt" || true
cp -r "$RUN/logs" "$RUN/train_summary.json" "$RUN/run.json" "$OUT/"
cat "$OUT/train.txt" | tail -3; cat "$OUT/eval_test.txt" "$OUT/eval_val.txt" "$OUT/predict.txt"
