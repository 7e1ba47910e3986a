#!/bin/bash
# Paper 000's GNN on the `medium` preset on a host of four GPUs, everything in ONE command of at most
# ten minutes (a host lent for a short while may be gone before a second command; on 2026-11-27 it
# was, twice, and the store and runs with it). Figures go to $OUT, packed at the end into
# $OUT/medium_run.tgz (the device tool returns few files) without anything large.
#   OUT=/tmp/out bash benchmarks/gnn_medium_gpu_run.sh
#   OUT=/tmp/out2 MORE=1 bash benchmarks/gnn_medium_gpu_run.sh   # if the host is still held: the same
#       eight runs resumed for another command, then evaluated again
# On the lent hosts (no anny, pymeshlab or warp installed): first the uploads (.gpu/a with the
# medium garments' cache, then .gpu/b with the body's), then this with `source .gpu/c/activate` and
# DRAPE_CACHE_DIR pointing at the uploaded cache; the three calls back to back, since a host left
# idle for 30 s is given back with everything on it.
# 1. `drape generate --preset medium --device cuda:0,cuda:1,cuda:2`: one simulating process per GPU,
#    each a third of the 248 scenes (datagen/generate/devices.py). Meanwhile, alone on GPU 3, the
#    captured prediction's CUDA tests and the inference benchmark (eager, static, captured on one and
#    two streams, torch.compile).
# 2. Eight `drape train gnn` runs, two to a GPU, until EVAL_SECONDS before the deadline: the full
#    model with seeds 0 and 1 and the six ablation switches of §5.3.
# 3. `drape evaluate --split test`: the full runs on every test frame, the ablations on a third;
#    Figure 10 and its table (benchmarks/gnn_ablations.py).
# On a one-GPU host: GEN_DEVICES=cuda:0 and a RUNLIST whose runs all name GPU 0.
# On a two-GPU host (TWO_GPUS=1): the store on both GPUs, the CUDA tests beside the generation on
# GPU 1, four runs to a GPU, and the inference benchmark after the evaluations (alone on GPU 0) in
# the command that evaluates. Switches for a session of several commands:
#   NO_EVAL=1          train only (a later MORE=1 command evaluates)
#   EVAL_RUNS="a b"    evaluate these runs on the test split (default: all; Figure 10 is always all)
#   BENCH_AFTER=1      the inference benchmark (torch.compile rows) after the evaluations
#   FULL_FRAMES=N      evaluate the full runs on N test frames drawn evenly (default: all 2,580)
# The full runs' best weights come back as $OUT/run_full-s*.tgz (a run directory for `drape evaluate`).
set -o pipefail
OUT=${OUT:-/tmp/gnn-medium-out}; STORE=${STORE:-/tmp/medium.zarr}; RUNS=${RUNS:-/tmp/runs}
BUDGET=${BUDGET:-570}; T0=$(date +%s); DEADLINE=$((T0 + BUDGET)); DEVICE=${DEVICE:-cuda}
EVAL_SECONDS=${EVAL_SECONDS:-300}  # 150 did not do: eight evaluations at once took ~250 s on 4 x H200
GEN_ARGS=${GEN_ARGS:---preset medium}  # a config file instead, for a dry run on the CPU
GEN_DEVICES=${GEN_DEVICES:-cuda:0,cuda:1,cuda:2}  # GPU 3 times inference meanwhile, alone on its card
TEST_GPU=${TEST_GPU:-3}  # NO_TESTS=1: neither the CUDA tests nor the benchmark beside the generation
if [ -n "$TWO_GPUS" ]; then
  GEN_DEVICES=cuda:0,cuda:1; TEST_GPU=1; NO_BENCH_DURING=1; export OMP_NUM_THREADS=3
  RUNLIST=${RUNLIST:-"full-s0:full:0:0 full-s1:full:1:1 no_decomposition:no_decomposition:0:0 output_limit:output_limit:0:1
no_parser:no_parser:0:0 concat_parser:concat_parser:0:1 single_step:single_step:0:0 no_pooling:no_pooling:0:1"}
fi
BENCH_SECONDS_AFTER=${BENCH_SECONDS_AFTER:-0}; [ -n "$BENCH_AFTER" ] && BENCH_SECONDS_AFTER=${BENCH_SECONDS:-150}
mkdir -p "$OUT" "$RUNS"
# eight trainings and evaluations share 64 cores: without a limit each takes a thread per core
# (on 2026-11-27 eight evaluations of 960 frames did not end in 290 s)
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-6}
# GPU utilisation every 5 s (issue 24: is the loader the limit?); disowned, so `wait` does not
# wait for it (a bare `wait` on it held a command to its time limit on 2026-11-27)
if [ "$DEVICE" = cuda ]; then
  nvidia-smi --query-gpu=timestamp,index,utilization.gpu,memory.used --format=csv,noheader -l 5 \
    >> "$OUT/gpu_util.csv" 2>/dev/null & SMI=$!; disown $SMI
  nvidia-smi --query-gpu=index,name,memory.total --format=csv > "$OUT/gpus.txt"
fi
filter() { grep -v "^Module\|^Warp\|^   \|CUDA Toolkit\|Devices:\|Kernel cache"; }
# name ablation seed gpu
RUNLIST=${RUNLIST:-"full-s0:full:0:0 no_decomposition:no_decomposition:0:0 full-s1:full:1:1 output_limit:output_limit:0:1
no_parser:no_parser:0:2 concat_parser:concat_parser:0:2 single_step:single_step:0:3 no_pooling:no_pooling:0:3"}
sed "s/^seed: 0/seed: 1/" "${CONFIG:=benchmarks/configs/gnn_medium.yaml}" > "$RUNS/gnn_medium_seed1.yaml"
config_of() { [ "$1" = 1 ] && echo "$RUNS/gnn_medium_seed1.yaml" || echo "$CONFIG"; }
minutes_left() { python -c "print(max(0.5, round(($1 - $(date +%s)) / 60, 2)))"; }

# 1. the store (MORE=1: kept from the last command on this host; the runs resume instead)
if [ -z "$MORE" ]; then
  ( time python -m datagen.cli generate $GEN_ARGS --out "$STORE" --device "$GEN_DEVICES" ) > "$OUT/generate.log" 2>&1 &
  GEN=$!
  if [ "$DEVICE" = cuda ] && [ -z "$NO_TESTS" ]; then  # on GPU 3, which has no share of the simulation
    # (about as long as the generation: the runs start when both are done; torch.compile comes last,
    # so the time limit costs at most its row); on two GPUs only the tests, beside a simulation
    ( CUDA_VISIBLE_DEVICES=$TEST_GPU timeout 90 python -m pytest -q -p no:cacheprovider tests/training/test_gnn.py \
        -k "captured or static or rounds or magnitude" > "$OUT/captured_test.txt" 2>&1
      [ -n "$NO_BENCH_DURING" ] || CUDA_VISIBLE_DEVICES=$TEST_GPU timeout ${BENCH_SECONDS:-120} python -u \
        benchmarks/bench_gnn.py --vertices 3500 --batch 60 --device cuda --seconds 3 --compile > "$OUT/bench_gnn_b60.txt" 2>&1 ) &
    BENCH=$!
  fi
  if ! wait $GEN; then  # the staged samples are kept: one device finishes what is left
    echo "== generating on $GEN_DEVICES failed ($(tail -1 "$OUT/generate.log")); resuming on cuda:0"
    ( time python -m datagen.cli generate $GEN_ARGS --out "$STORE" --device "${GEN_DEVICES%%,*}" ) >> "$OUT/generate.log" 2>&1
  fi
  filter < "$OUT/generate.log" | tail -n 20
  python -m datagen.cli validate "$STORE" 2>&1 | tail -3 | tee "$OUT/validate.txt"
  python -m datagen.cli info "$STORE" > "$OUT/info.txt" 2>&1
  du -sh "$STORE" | tee -a "$OUT/info.txt"
  [ -n "$BENCH" ] && wait $BENCH
fi

# 2. eight runs until the evaluations' share of the time
[ -n "$NO_EVAL" ] && EVAL_SECONDS=0
# each run's start and end are outside its --max-minutes: 45 s was enough for two runs to a card,
# not for four (on 2026-11-27 the first two-GPU command ran past the device's 600 s limit)
START_END=${START_END:-45}; [ -n "$TWO_GPUS" ] && START_END=${START_END_TWO:-100}
left=$(minutes_left $((DEADLINE - EVAL_SECONDS - BENCH_SECONDS_AFTER - START_END)))
mode=--force
if [ -n "$MORE" ]; then  # the limit counts the minutes trained before, so it grows by what is left
  mode=--resume; left=$(python -c "print(round($(cat "$RUNS/minutes.txt") + $left, 2))")
fi
echo "$left" > "$RUNS/minutes.txt"
echo "== training $(wc -w <<< "$RUNLIST") runs to $left minutes ($mode)"
TRAIN_START=$(date +%s)
pids=""
for r in $RUNLIST; do
  IFS=: read -r name ablation seed gpu <<< "$r"
  CUDA_VISIBLE_DEVICES=$gpu python -m datagen.cli train gnn --data "$STORE" --out "$RUNS/$name" \
    --config "$(config_of "$seed")" --ablation "$ablation" --device "$DEVICE" $mode \
    --max-minutes "$left" >> "$OUT/train_$name.log" 2>&1 & pids="$pids $!"
done
# a watchdog ends the runs (SIGTERM, then SIGKILL) if they outlast their share, so that the
# evaluations and the packing of $OUT still happen; the checkpoints of finished epochs stay
HARD=$((DEADLINE - EVAL_SECONDS - BENCH_SECONDS_AFTER - 20))
( while [ "$(date +%s)" -lt "$HARD" ]; do sleep 2; done
  echo "== watchdog: runs still going at their hard limit; stopping them" >> "$OUT/watchdog.txt"
  kill -TERM $pids 2>/dev/null; sleep 15; kill -KILL $pids 2>/dev/null ) > /dev/null 2>&1 &
WATCH=$!; disown $WATCH
wait $pids
pkill -P $WATCH 2>/dev/null; kill $WATCH 2>/dev/null
TRAIN_END=$(date +%s)
for r in $RUNLIST; do IFS=: read -r name _ <<< "$r"; echo "-- $name: $(tail -1 "$OUT/train_$name.log" | cut -c1-200)"; done

# 3. evaluations, ended in time for the logs and Figure 10
left=$((DEADLINE - 25 - BENCH_SECONDS_AFTER - $(date +%s)))
pids=""
[ -n "$NO_EVAL" ] && RUNS_TO_EVAL="" || RUNS_TO_EVAL=$RUNLIST
for r in $RUNS_TO_EVAL; do
  IFS=: read -r name ablation seed gpu <<< "$r"
  [ -n "$EVAL_RUNS" ] && ! grep -qw -- "$name" <<< "$EVAL_RUNS" && continue
  frames=""; [ -n "$FULL_FRAMES" ] && frames="--max-frames $FULL_FRAMES"
  [ "$ablation" = full ] || frames="--max-frames ${ABLATION_FRAMES:-860}"
  CUDA_VISIBLE_DEVICES=$gpu timeout "$left" python -m datagen.cli evaluate "$RUNS/$name" --data "$STORE" --split test \
    --json "$RUNS/$name/eval_test.json" --device "$DEVICE" $frames > "$OUT/eval_$name.log" 2>&1 & pids="$pids $!:$name"
done
for p in $pids; do  # an evaluation stopped by its limit says so (it left an empty log on 2026-11-27)
  wait "${p%%:*}"; rc=$?
  [ $rc = 124 ] && echo "evaluation stopped by its time limit of $left s (EVAL_SECONDS=$EVAL_SECONDS)" | tee -a "$OUT/eval_${p#*:}.log"
done
for r in $RUNLIST; do
  IFS=: read -r name _ <<< "$r"; rm -rf "$OUT/logs_$name"; cp -r "$RUNS/$name/logs" "$OUT/logs_$name"
  cp "$RUNS/$name"/*.json "$OUT/logs_$name/" 2>/dev/null
done
python benchmarks/gnn_ablations.py $(for r in $RUNLIST; do echo "${r%%:*}=$RUNS/${r%%:*}"; done) --out "$OUT" 2>&1 | tail -14
[ -f "$OUT/eval_full-s0.log" ] && filter < "$OUT/eval_full-s0.log" | tail -40
if [ -n "$BENCH_AFTER" ] && [ "$DEVICE" = cuda ]; then  # alone on GPU 0 now: the compiled rows only
  CUDA_VISIBLE_DEVICES=0 timeout "$BENCH_SECONDS_AFTER" python -u benchmarks/bench_gnn.py --vertices 3500 --batch 60 \
    --device cuda --seconds 3 --compile --compile-only --max-autotune --tf32 > "$OUT/bench_gnn_compiled.txt" 2>&1
  filter < "$OUT/bench_gnn_compiled.txt" | tail -8
fi
[ -n "$SMI" ] && kill "$SMI" 2>/dev/null
# mean GPU utilisation per card over the training's samples (the rows between its start and end)
[ -f "$OUT/gpu_util.csv" ] && python - "$OUT/gpu_util.csv" "$TRAIN_START" "$TRAIN_END" <<'PY' | tee "$OUT/gpu_util_training.txt"
import csv, sys
from datetime import datetime
start, end = float(sys.argv[2]), float(sys.argv[3])
use = {}
for row in csv.reader(open(sys.argv[1])):
    try:
        t = datetime.strptime(row[0].strip(), "%Y/%m/%d %H:%M:%S.%f").timestamp()
        gpu, util = int(row[1]), float(row[2].split()[0])
    except (ValueError, IndexError):
        continue
    if start <= t <= end:
        use.setdefault(gpu, []).append(util)
for gpu, u in sorted(use.items()):
    print(f"GPU {gpu}: {sum(u) / len(u):.0f} % utilisation on average over {len(u)} samples of the training")
PY
# the full runs' best weights (no optimiser state: ~11 MB each), so that a run can be evaluated
# again elsewhere, on the CPU too, when the host is gone (on 2026-11-27 the evaluations ran out of time
# and the checkpoints went with the host)
for name in full-s0 full-s1; do
  [ -f "$RUNS/$name/checkpoints/best.ckpt" ] || continue
  python - "$RUNS/$name" "$OUT/run_$name" <<'PY'
import shutil, sys
from pathlib import Path
import torch
run, out = Path(sys.argv[1]), Path(sys.argv[2])
(out / "checkpoints").mkdir(parents=True, exist_ok=True)
ckpt = torch.load(run / "checkpoints" / "best.ckpt", map_location="cpu", weights_only=False)
torch.save({k: v for k, v in ckpt.items() if k not in ("optimizer_states", "lr_schedulers", "callbacks", "loops")},
           out / "checkpoints" / "best.ckpt")
for f in ("run.json", "train_summary.json"):
    if (run / f).exists():
        shutil.copy(run / f, out / f)
PY
  tar czf "$OUT/run_$name.tgz" -C "$OUT" "run_$name" && rm -rf "$OUT/run_$name"
done
tar czf /tmp/medium_run.tgz --exclude='*.ckpt' --exclude='run_*.tgz' --exclude='events.out.*' -C "$(dirname "$OUT")" "$(basename "$OUT")"
mv /tmp/medium_run.tgz "$OUT/"
ls -la "$OUT/medium_run.tgz"
