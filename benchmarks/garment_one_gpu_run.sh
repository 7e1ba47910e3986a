#!/bin/bash
# Issue 27 on ONE GPU in three commands of at most ten minutes, the machine kept warm between them:
#   OUT=$OUT PART=1 bash benchmarks/garment_one_gpu_run.sh   the paper-motion store in one batch (~9.5 min;
#       carry warp's kernel cache, or the compilation does not fit)
#   OUT=$OUT PART=2 bash ...   the garment regressors in drape's skinned frame at 3e-4 and at paper 001's 1e-3,
#       with the learned and the zero BOS, per template (12 runs at once, MAXMIN minutes each), evaluated on
#       the validation and the test split (benchmarks/garment_table.py chooses per template on validation);
#       beside them a motion generator for the refinement's sampled motions (GEN_MINUTES)
#   OUT=$OUT PART=3 bash ...   each template's chosen regressor refined (§3.4) on motions sampled from that
#       generator, the refined runs evaluated on the test split (the share of vertices inside the body on
#       test motions, before and after), the table again, and a clothed sample per template (USD + GIF;
#       usd-core must be importable: USD=DIR, a `pip install --target DIR` of its wheel)
#   OUT=$OUT PART=all MO=DIR bash ...   the three parts back to back in the background, and the generator beside them
#       from the start (below); then OUT=$OUT PART=poll WAIT=540 bash ... in each later command until PART=all is done
# REFINE='--samples 4 --steps 2': arguments for `drape train refine` (a dry run on a CPU with CONFIG=micro.yaml
# GARMENTS=skirt DEV=cpu MAXMIN=0.3 GEN_MINUTES=0.3).
# Everything persistent lives in W (default /tmp/p27); each part's logs come back as $OUT/part$PART.tgz
# (the device tool returns at most eight files), the clothed samples' GIFs beside it.
# Runs: PART=1 on an H100 (2026-11-27, eighth session): 252 scenes in 544 s, 223 pass, 98.3 garment-frames/s
# end to end, valid; the machine went back before PART=2. PART=all then poll x3 on an H200 (ninth session): all three
# parts in 25.7 minutes with the generator beside them (docs/bench/garment_one_h200_20261127m/).
set -o pipefail
OUT=${OUT:?}; PART=${PART:?}; W=${W:-/tmp/p27}; STORE=$W/paper-motion.zarr; RUNS=$W/runs; EV=$W/eval
mkdir -p "$OUT" "$W" "$RUNS" "$EV"
D="python -m datagen.cli"
log="$OUT/part$PART.log"
case "$PART" in
1)
  OUT=$W/gen STORE=$STORE RUNS=$RUNS PHASE=gen BATCH=252 LIMIT=${LIMIT:-9.6} bash benchmarks/paper_motion_gpu_run.sh 2>&1 | tee "$log"
  cp -r "$W/gen" "$OUT/gen" ;;
2)
  [ "${GEN:-1}" = 1 ] && $D train motion --data "$STORE" --out "$RUNS/motion" --config benchmarks/configs/motion_paper.yaml \
     --device ${DEV:-cuda} --force --max-minutes "${GEN_MINUTES:-5.5}" > "$EV/train_motion.log" 2>&1 &
  OUT=$EV STORE=$STORE RUNS=$RUNS PHASE=regress MAXMIN=${MAXMIN:-5} \
     VARIANTS=${VARIANTS:-"s3:garment_lr3e-4_skinned s1:garment_lr1e-3_skinned"} bash benchmarks/paper_motion_gpu_run.sh 2>&1 | tee "$log"
  wait
  [ "${GEN:-1}" = 1 ] && tail -2 "$EV/train_motion.log" | tee -a "$log" ;;
3)
  [ -n "$USD" ] && export PYTHONPATH=$PYTHONPATH:$USD
  chosen=$(sed -n 's/^\([a-z]*\): chosen on the validation split: \(.*\)$/\2/p' "$EV/table.txt")
  echo "chosen on the validation split: $chosen" | tee "$log"
  for n in $chosen; do
    $D train refine --garment-model "$RUNS/$n" --motion-model "$RUNS/motion" --latent posterior --out "$RUNS/${n}_refined" ${REFINE:-} \
       --device ${DEV:-cuda} --force > "$EV/refine_$n.log" 2>&1 &
  done
  wait
  for n in $chosen; do
    $D evaluate "$RUNS/${n}_refined" --split test --device ${DEV:-cuda} --json "$EV/eval_${n}_refined_test.json" > "$EV/eval_${n}_refined_test.log" 2>&1 &
  done
  wait
  for n in $chosen; do
    mkdir -p "$EV/runs/${n}_refined"; cp "$RUNS/${n}_refined/run.json" "$EV/runs/${n}_refined/" 2>/dev/null
    echo "== refine $n"; grep -v "it/s\]$" "$EV/refine_$n.log" | tail -4
  done 2>&1 | tee -a "$log"
  python benchmarks/garment_table.py "$EV" | tee "$EV/table_refined.txt" | tee -a "$log"
  mkdir -p "$EV/clothed"
  for n in $chosen; do
    g=${n%%_*}
    $D sample clothed --motion-model "$RUNS/motion" --garment-model "$RUNS/${n}_refined" --label dance_disco --seed 0 \
       --out "$EV/clothed/${g}_dance_disco.usd" --video "$EV/clothed/${g}_dance_disco.gif" --device ${DEV:-cuda} > "$EV/clothed/$g.log" 2>&1
    echo "== clothed $g: exit $?"; tail -3 "$EV/clothed/$g.log"
  done 2>&1 | tee -a "$log"
  cp "$EV"/clothed/*.gif "$OUT/" 2>/dev/null ;;
all)  # the three parts one after the other in a process session of their own (setsid), so that no part waits
  # for the next command; beside them, from the start, the motion generator on a motions-only store MO
  # (benchmarks/configs/paper_motion_motions_only.yaml, made on a CPU and carried) for GEN_MINUTES, at the
  # settings of the longest generator run (benchmarks/configs/motion_paper_long.yaml). Then call PART=poll.
  MO=${MO:?a motions-only store}; : > "$W/progress"; rm -f "$W/done"
  ( $D train motion --data "$MO" --out "$RUNS/motion" --config benchmarks/configs/motion_paper_long.yaml --device ${DEV:-cuda} \
      --force --max-minutes "${GEN_MINUTES:-14}" > "$EV/train_motion.log" 2>&1; echo "$(date +%T) generator exit $?" >> "$W/progress" ) &
  for p in 1 2 3; do
    [ $p = 3 ] && { wait; echo "$(date +%T) generator: $(grep '^trained' "$EV/train_motion.log")" >> "$W/progress"; }
    echo "$(date +%T) part $p starts" >> "$W/progress"
    OUT=$W/out$p PART=$p GEN=0 LIMIT=${LIMIT:-14} USD=${USD:-/root/stash/usd} bash "$0" > "$W/part$p.out" 2>&1
    echo "$(date +%T) part $p exit $?" >> "$W/progress"
  done
  touch "$W/done"; exit 0 ;;
poll)  # wait for PART=all (WAIT seconds at most), then bring back what it has written so far
  t0=$SECONDS; while [ ! -f "$W/done" ] && [ $((SECONDS - t0)) -lt "${WAIT:-540}" ]; do sleep 5; done
  cat "$W/progress"; for p in 1 2 3; do [ -f "$W/part$p.out" ] && { echo "== part $p"; grep -v "it/s\]$" "$W/part$p.out" | tail -${TAIL:-12}; }; done
  grep -v "it/s\]$" "$EV/train_motion.log" 2>/dev/null | tail -3
  cp "$EV"/clothed/*.gif "$OUT/" 2>/dev/null
  tar czf "$OUT/state.tgz" --exclude='*.ckpt' --exclude='events.out.*' --exclude='*.gif' --exclude='*.usd' -C "$W" \
      $(cd "$W" && ls -d progress part*.out out1/gen out2/part2.log out3/part3.log eval runs/motion/logs runs/motion/run.json runs/motion/train_summary.json 2>/dev/null)
  ls -la "$OUT"; exit 0 ;;
esac
tar czf "$OUT/part$PART.tgz" --exclude='*.ckpt' --exclude='events.out.*' --exclude='*.gif' -C "$W" $( [ "$PART" = 1 ] && echo gen || echo eval)
ls -la "$OUT"
