#!/bin/bash
# Paper 001 on one GPU in phases that each fit one 10-minute command; figures and logs go to $OUT.
#   OUT=/tmp/o PHASE=gen LIMIT=8.5 bash benchmarks/paper_motion_gpu_run.sh   the paper-motion store
#       (`drape generate --time-limit`: repeat the call until it says the store is complete; BATCH=252:
#       the whole preset in one batch, one command on one H100 or H200 with the kernels compiled before)
#   OUT=/tmp/o PHASE=train bash ...   the motion generator at λ_KL = 1e-5 (the paper's), 1e-4 and 1e-3
#       (motion_lr3e-4 in MOTIONS: at 3x the paper's rate),
#       and without the vertex loss (Table 8), and the garment regressor per template (skirt, tshirt,
#       pants) with the learned and a zero BOS (Table 9), all on the GPU at once
#       (MAXMIN=M: M minutes each instead of the configs'; MOTIONS='motion' GARMENTS='': the generator alone,
#       alone on the GPU instead of beside six other runs; STORE=DIR with PHASE=train|eval: an existing store,
#       e.g. one of benchmarks/configs/paper_motion_motions_only.yaml made on a CPU, for the generator alone)
#   OUT=/tmp/o PHASE=more TOTAL=16 bash ...   every run of PHASE=train resumed for another command, to
#       TOTAL minutes of training in all (repeat with a larger TOTAL)
#   OUT=/tmp/o PHASE=regress MAXMIN=7 bash ...   the garment regressor alone, in one command: per template
#       (GARMENTS) and frame (VARIANTS, NAME:CONFIG of benchmarks/configs: the paper's frame relative to
#       the translation and drape's relative to the skinned template, both at 3e-4), the learned and the
#       zero BOS, all at once; then each evaluated on the validation and the test split, and
#       benchmarks/garment_table.py's table (the validation split picks per template)
#   OUT=/tmp/o PHASE=eval bash ...    the validation split picks the KL weight and the latent (prior or
#       per-label posterior fit) by generated FID; then Tables 3, 4, 6, 7, 8, 9 on the test split;
#       refinement of the skirt (§3.4); sampled motions per label (for the contact sheets); a clothed
#       sample as USD + GIF
# CONFIG=benchmarks/configs/paper_motion_coarse.yaml GARMENTS='skirt pants' (all phases): the coarse store that
# one command makes (docs/training.md's runs). Each phase writes many files into $OUT: where only a few files come back from a machine, tar $OUT.
set -o pipefail
OUT=${OUT:-/tmp/pm-out}; STORE=${STORE:-/tmp/pm/paper-motion.zarr}; RUNS=${RUNS:-/tmp/pm/runs}
PHASE=${PHASE:-gen}; LIMIT=${LIMIT:-8.5}; GARMENTS=${GARMENTS-skirt tshirt pants}
MOTIONS=${MOTIONS:-motion motion_kl1e-3 motion_novl}  # motion_kl1e-4 too, where the GPU has room
DEV=${DEV:-cuda}
SOURCE=${CONFIG:---preset paper-motion}  # CONFIG=FILE: another dataset config
mkdir -p "$OUT" "$(dirname "$STORE")" "$RUNS"
D="python -m datagen.cli"
quiet() { grep -v "^Module\|^Warp\|^   \|^ *\"cuda\|^ *\"cpu\|CUDA Toolkit\|Devices:\|Kernel cache" "$@"; }
case "$PHASE" in
gen)
  n=$(ls "$OUT"/generate_*.log 2>/dev/null | wc -l)
  $D generate $SOURCE --out "$STORE" --device $DEV --time-limit "$LIMIT" ${BATCH:+--batch-size $BATCH} > "$OUT/generate_$n.log" 2>&1
  rc=$?; echo "generate exit $rc"; quiet "$OUT/generate_$n.log" | grep -v "^scene \|it/s\]$" | tail -30
  if [ $rc -eq 0 ]; then
    $D info "$STORE" > "$OUT/info.txt" 2>&1; $D validate "$STORE" > "$OUT/validate.txt" 2>&1; echo "validate exit $?"
    grep "^scene .*failed" "$OUT"/generate_*.log | sed 's/.*failed at frame [0-9]*: //; s/:.*//' | sort | uniq -c
    du -sh "$STORE"
  fi ;;
train|more)  # more: another command for every run of train, to TOTAL minutes in all (Lightning's timer
  # counts the minutes already trained; the plateau schedule and early stopping carry on where they were)
  if [ "$PHASE" = more ]; then common="--data $STORE --device $DEV --resume --max-minutes ${TOTAL:-16}"
  else common="--data $STORE --device $DEV --force${MAXMIN:+ --max-minutes $MAXMIN}"; fi
  tm() { $D train motion $common --out "$RUNS/$1" --config "$2" $3 > "$OUT/${PHASE}_$1.log" 2>&1; }
  for r in $MOTIONS; do  # motion: the paper's; motion_klX: λ_KL = X; motion_novl: without L_V^B
    case $r in
      motion_novl) tm $r benchmarks/configs/motion_paper.yaml --no-vertex-loss & ;;
      motion_kl*|motion_lr*) tm $r "benchmarks/configs/motion_paper_${r#motion_}.yaml" & ;;
      *) tm $r benchmarks/configs/motion_paper.yaml & ;;
    esac
  done
  for g in $GARMENTS; do
    $D train garment $common --garment $g --out "$RUNS/$g" --config benchmarks/configs/garment_paper.yaml > "$OUT/${PHASE}_$g.log" 2>&1 &
    $D train garment $common --garment $g --zero-bos --out "$RUNS/${g}_zero_bos" --config benchmarks/configs/garment_paper.yaml > "$OUT/${PHASE}_${g}_zero_bos.log" 2>&1 &
  done
  wait
  for r in $MOTIONS $(for g in $GARMENTS; do echo $g ${g}_zero_bos; done); do
    mkdir -p "$OUT/runs/$r"; cp -r "$RUNS/$r/logs" "$RUNS/$r/run.json" "$OUT/runs/$r/" 2>/dev/null
    cp "$RUNS/$r/train_summary.json" "$OUT/runs/$r/" 2>/dev/null; echo "== $r"; tail -3 "$OUT/${PHASE}_$r.log"
  done ;;
regress)
  VARIANTS=${VARIANTS:-"t:garment_lr3e-4 s:garment_lr3e-4_skinned"}
  names=""
  for g in $GARMENTS; do for v in $VARIANTS; do for b in learned zero; do
    n=${g}_${v%%:*}; bos=""; [ $b = zero ] && { n=${n}_zero_bos; bos=--zero-bos; }; names="$names $n"
    $D train garment --data "$STORE" --device $DEV --force --max-minutes "${MAXMIN:-7}" --garment $g $bos --out "$RUNS/$n" \
      --config "benchmarks/configs/${v#*:}.yaml" > "$OUT/train_$n.log" 2>&1 &
  done; done; done
  wait
  for n in $names; do for split in val test; do
    $D evaluate "$RUNS/$n" --split $split --device $DEV --json "$OUT/eval_${n}_$split.json" > "$OUT/eval_${n}_$split.log" 2>&1 &
  done; done
  wait
  for n in $names; do mkdir -p "$OUT/runs/$n"; cp -r "$RUNS/$n/logs" "$RUNS/$n/run.json" "$RUNS/$n/train_summary.json" "$OUT/runs/$n/" 2>/dev/null; done
  python benchmarks/garment_table.py "$OUT" | tee "$OUT/table.txt" ;;
eval)
  ev() { $D evaluate "$RUNS/$1" --split $2 --device $DEV --json "$OUT/eval_${1}_$2.json" $3 > "$OUT/eval_${1}_$2.log" 2>&1; }
  # 1. the validation split chooses the KL weight and where Z is drawn from (lowest generated FID)
  CHOICES=$(for r in $MOTIONS; do [ "$r" != motion_novl ] && echo $r; done)
  for r in $CHOICES; do ev $r val "--repetitions 10" & done
  for g in $GARMENTS; do ev $g test & ev ${g}_zero_bos test & done
  wait
  read -r best latent < <(python benchmarks/choose_motion_run.py "$OUT" $CHOICES | tee "$OUT/choice.txt" | tail -1)
  best=${best:-motion}; latent=${latent:-posterior}
  echo "chosen on the validation split: $best, latent $latent"; cat "$OUT/choice.txt"
  # 2. the test split for every motion run; the refinement and samples from the chosen one
  for r in $MOTIONS; do ev $r test & done
  $D train refine --garment-model "$RUNS/skirt" --motion-model "$RUNS/$best" --latent $latent --out "$RUNS/skirt_refined" --device $DEV --force > "$OUT/refine_skirt.log" 2>&1 &
  $D sample motion "$RUNS/$best" --label all --latent $latent --count 4 --seed 0 --out "$OUT/samples" > "$OUT/sample_motion.log" 2>&1
  wait
  ev skirt_refined test
  $D sample clothed --motion-model "$RUNS/$best" --garment-model "$RUNS/skirt_refined" --latent $latent --label dance_disco --seed 0 \
     --out "$OUT/clothed_skirt_dance_disco.usd" --video "$OUT/clothed_skirt_dance_disco.gif" --device $DEV > "$OUT/clothed.log" 2>&1
  for f in "$OUT"/eval_*.log "$OUT/refine_skirt.log" "$OUT/clothed.log"; do echo "== $f"; quiet "$f" | tail -30; done ;;
esac
