#!/bin/bash
# Paper 001 on one GPU in phases that each fit one 10-minute command; figures and logs go to $OUT.
#   OUT=/tmp/o PHASE=gen LIMIT=8.5 bash benchmarks/paper_motion_gpu_run.sh   the paper-motion store
#       (`drape generate --time-limit`: repeat the call until it says the store is complete)
#   OUT=/tmp/o PHASE=train bash ...   the motion generator with and without the vertex loss (Table 8)
#       and the garment regressor per template (skirt, tshirt, pants; the skirt also with a zero BOS,
#       Table 9), all on the GPU at once
#   OUT=/tmp/o PHASE=eval bash ...    Tables 3, 4, 6, 7, 9; refinement of the skirt (§3.4); sampled
#       motions per label (for the contact sheet); a clothed sample as USD + GIF
# CONFIG=benchmarks/configs/paper_motion_coarse.yaml GARMENTS='skirt pants' (all phases): the coarse store that
# one command makes (docs/training.md's runs). Each phase writes many files into $OUT: where only a few files come back from a machine, tar $OUT.
set -o pipefail
OUT=${OUT:-/tmp/pm-out}; STORE=${STORE:-/tmp/pm/paper-motion.zarr}; RUNS=${RUNS:-/tmp/pm/runs}
PHASE=${PHASE:-gen}; LIMIT=${LIMIT:-8.5}; GARMENTS=${GARMENTS:-skirt tshirt pants}
SOURCE=${CONFIG:---preset paper-motion}  # CONFIG=FILE: another dataset config
mkdir -p "$OUT" "$(dirname "$STORE")" "$RUNS"
D="python -m datagen.cli"
quiet() { grep -v "^Module\|^Warp\|^   \|^ *\"cuda\|^ *\"cpu\|CUDA Toolkit\|Devices:\|Kernel cache" "$@"; }
case "$PHASE" in
gen)
  n=$(ls "$OUT"/generate_*.log 2>/dev/null | wc -l)
  $D generate $SOURCE --out "$STORE" --device cuda --time-limit "$LIMIT" > "$OUT/generate_$n.log" 2>&1
  rc=$?; echo "generate exit $rc"; quiet "$OUT/generate_$n.log" | grep -v "^scene \|it/s\]$" | tail -30
  if [ $rc -eq 0 ]; then
    $D info "$STORE" > "$OUT/info.txt" 2>&1; $D validate "$STORE" > "$OUT/validate.txt" 2>&1; echo "validate exit $?"
    grep "^scene .*failed" "$OUT"/generate_*.log | sed 's/.*failed at frame [0-9]*: //; s/:.*//' | sort | uniq -c
    du -sh "$STORE"
  fi ;;
train)
  common="--data $STORE --device cuda --force"
  $D train motion $common --out "$RUNS/motion" --config benchmarks/configs/motion_paper.yaml > "$OUT/train_motion.log" 2>&1 &
  $D train motion $common --out "$RUNS/motion_novl" --config benchmarks/configs/motion_paper.yaml --no-vertex-loss > "$OUT/train_motion_novl.log" 2>&1 &
  for g in $GARMENTS; do
    $D train garment $common --garment $g --out "$RUNS/$g" --config benchmarks/configs/garment_paper.yaml > "$OUT/train_$g.log" 2>&1 &
  done
  $D train garment $common --garment skirt --zero-bos --out "$RUNS/skirt_zero_bos" --config benchmarks/configs/garment_paper.yaml > "$OUT/train_skirt_zero_bos.log" 2>&1 &
  wait
  for r in motion motion_novl $GARMENTS skirt_zero_bos; do
    mkdir -p "$OUT/runs/$r"; cp -r "$RUNS/$r/logs" "$RUNS/$r/run.json" "$OUT/runs/$r/" 2>/dev/null
    cp "$RUNS/$r/train_summary.json" "$OUT/runs/$r/" 2>/dev/null; echo "== $r"; tail -3 "$OUT/train_$r.log"
  done ;;
eval)
  $D evaluate "$RUNS/motion" --split test --device cuda --json "$OUT/eval_motion.json" > "$OUT/eval_motion.log" 2>&1 &
  $D evaluate "$RUNS/motion_novl" --split test --device cuda --json "$OUT/eval_motion_novl.json" > "$OUT/eval_motion_novl.log" 2>&1 &
  for r in $GARMENTS skirt_zero_bos; do
    $D evaluate "$RUNS/$r" --split test --device cuda --json "$OUT/eval_$r.json" > "$OUT/eval_$r.log" 2>&1 &
  done
  $D train refine --garment-model "$RUNS/skirt" --motion-model "$RUNS/motion" --out "$RUNS/skirt_refined" --device cuda --force > "$OUT/refine_skirt.log" 2>&1 &
  labels=$(python -c "import json, sys; print(' '.join(json.load(open(sys.argv[1]))['labels']))" "$RUNS/motion/run.json")
  for l in $labels; do $D sample motion "$RUNS/motion" --label "$l" --count 4 --seed 0 --out "$OUT/samples/$l" >> "$OUT/sample_motion.log" 2>&1; done
  wait
  $D evaluate "$RUNS/skirt_refined" --split test --device cuda --json "$OUT/eval_skirt_refined.json" > "$OUT/eval_skirt_refined.log" 2>&1
  $D sample clothed --motion-model "$RUNS/motion" --garment-model "$RUNS/skirt_refined" --label dance_disco --seed 0 \
     --out "$OUT/clothed_skirt_dance_disco.usd" --video "$OUT/clothed_skirt_dance_disco.gif" --device cuda > "$OUT/clothed.log" 2>&1
  for f in "$OUT"/eval_*.log "$OUT/refine_skirt.log" "$OUT/clothed.log"; do echo "== $f"; quiet "$f" | tail -30; done ;;
esac
