#!/bin/bash
# Issue 26 on ONE GPU: paper 001's motion generator trained far longer than one ten-minute command, in
# the background across commands, with and without the vertex loss (Table 8), then Tables 3, 4 and 8.
#   OUT=$OUT PART=1 MO=.simbench/mo.zarr GEN_MINUTES=18 bash benchmarks/motion_long_gpu_run.sh
#       starts both runs in a process session of their own (setsid: they outlive the command, not the
#       machine) on a motions-only store made on a CPU (benchmarks/configs/paper_motion_motions_only.yaml),
#       then shows their progress until HOLD seconds have passed (the machine goes back when no command runs)
#   OUT=$OUT PART=2 bash ...   waits for both runs to end, then `drape evaluate` on the validation split
#       (benchmarks/choose_motion_run.py: where Z is drawn from) and the test split (20 generated sets),
#       and four sampled motions per label of the paper's run (benchmarks/sampled_motion_sheet.py draws them)
# Persistent files live in W (default /tmp/p26); each part's logs come back as $OUT/part$PART.tgz.
set -o pipefail
OUT=${OUT:?}; PART=${PART:?}; W=${W:-/tmp/p26}; RUNS=$W/runs; EV=$W/eval; HOLD=${HOLD:-565}
mkdir -p "$OUT" "$W" "$RUNS" "$EV"
D="python -m datagen.cli"
log="$OUT/part$PART.log"
progress() {
  for r in motion motion_novl; do
    printf '%s: ' "$r"; tr '\r' '\n' < "$EV/train_$r.log" 2>/dev/null | grep -o "Epoch [0-9]*" | tail -1
  done
}
case "$PART" in
1)
  MO=${MO:?the motions-only store}; cp -r "$MO" "$W/mo.zarr"
  for r in motion motion_novl; do
    extra=""; [ $r = motion_novl ] && extra=--no-vertex-loss
    setsid nohup $D train motion --data "$W/mo.zarr" --out "$RUNS/$r" --config "${CONFIG:-benchmarks/configs/motion_paper_long.yaml}" \
      --device ${DEV:-cuda} --force --max-minutes "${GEN_MINUTES:?}" $extra > "$EV/train_$r.log" 2>&1 < /dev/null &
  done
  while [ $SECONDS -lt "$HOLD" ]; do sleep 60; echo "$SECONDS s: $(progress | tr '\n' ' ')"; done 2>&1 | tee "$log" ;;
2)
  while pgrep -f "train motion" > /dev/null && [ $SECONDS -lt "${WAIT:-480}" ]; do sleep 15; done
  progress | tee "$log"
  for r in motion motion_novl; do
    tr '\r' '\n' < "$EV/train_$r.log" | grep -v "it/s\]$" | tail -3 | tee -a "$log"
    mkdir -p "$EV/runs/$r"; cp -r "$RUNS/$r/logs" "$RUNS/$r/run.json" "$RUNS/$r/train_summary.json" "$EV/runs/$r/" 2>/dev/null
  done
  ev() { $D evaluate "$RUNS/$1" --split $2 --device ${DEV:-cuda} --json "$EV/eval_${1}_$2.json" $3 > "$EV/eval_${1}_$2.log" 2>&1; }
  ev motion val "--repetitions 10" & ev motion test & ev motion_novl test & wait
  python benchmarks/choose_motion_run.py "$EV" motion | tee "$EV/choice.txt" | tee -a "$log"
  latent=$(tail -1 "$EV/choice.txt" | awk '{print $2}'); latent=${latent:-posterior}
  $D sample motion "$RUNS/motion" --label all --latent $latent --count 4 --seed 0 --out "$EV/samples" > "$EV/sample_motion.log" 2>&1
  for f in "$EV"/eval_*_test.log; do echo "== $f"; grep -v "^Module\|^Warp" "$f" | tail -22; done 2>&1 | tee -a "$log" ;;
esac
tar czf "$OUT/part$PART.tgz" --exclude='*.ckpt' --exclude='events.out.*' -C "$W" eval
ls -la "$OUT"
