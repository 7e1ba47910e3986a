#!/bin/bash
# Issue 25's speed figures and 23's one-GPU paper-motion, for one device session (three commands,
# each under 10 minutes; figures and logs to $OUT):
#   OUT=/tmp/o PHASE=profile bash benchmarks/sim_speed_gpu_run.sh   the profile at 64 and 256 scenes with
#       the projection's skip on and off (the same run: the reference), then Newton's VBD beside drape
#       at 64 scenes with self-collision on and off (needs .simbench/sim_inputs.npz and newton_runs.pkl,
#       or SIM_INPUTS=... NEWTON_RUNS=...; newton installed; NEWTON=0 leaves Newton out)
#   OUT=/tmp/o PHASE=paper-motion bash ...   `drape generate --preset paper-motion --batch-size 252` on one
#       GPU under `time`, stopped at 585 s (run PHASE=profile first on the same machine: it compiles the
#       kernels), with nvidia-smi sampled every 10 s
#   OUT=/tmp/o PHASE=six bash ...   the six 300-frame runs at the production settings (RUNS=...; SETS as in compare)
#   PHASE=figures bash ... (under setsid)   issue 25's figures in the background, one run after the other on an
#       otherwise idle card: Newton's VBD beside drape at 64 and 256 scenes, self-collision on and off (NEWTON=0:
#       not), then the throughput at 1, 16, 64 and 256 scenes, on and off; BATCHES=1,16: other batch sizes;
#       PROFILE=1,64: the profile at those batch sizes too; SIX=1: the six 300-frame runs; GNN_CACHE=dir:
#       `drape generate --preset paper-gnn --device cuda` from that cache, stopped at GNN_SECONDS (585);
#       SET=k=v,k=v: SolverConfig fields for every run (paper-gnn's too: the preset's config with them); logs in W (default /tmp/s25); then
#   OUT=$OUT PHASE=poll WAIT=540 bash ...   in each later command, until the figures are done
#   (NEWTON_BATCHES=64: Newton at those batch sizes only; NEWTON_SELF=on: with self-collision only;
#   NEWTON_LAUNCH: how Newton's side is launched (bench_newton.py --newton-launch), default graph, then
#   Newton alone launched from Python at NEWTON_PY_BATCHES (default 64; none: not); NEWTON_PROFILE=K: each
#   solver's top K kernels over one more frame, default 12)
#   OUT=/tmp/o PHASE=compare BASE=.bench_base SETS="- sweep_groups=1" bash ...   the profile at BATCHES (default
#       64,256), self-collision on, of an earlier tree (BASE: a copy of its datagen/ and benchmarks/, e.g.
#       `git archive REF datagen benchmarks | tar x -C .bench_base`; none: left out) and of this one at each
#       of SETS, one after the other on the same card
set -o pipefail
OUT=${OUT:-/tmp/speed-out}; PHASE=${PHASE:-profile}
SIM_INPUTS=${SIM_INPUTS:-.simbench/sim_inputs.npz}; NEWTON_RUNS=${NEWTON_RUNS:-.simbench/newton_runs.pkl}
RUNS=${RUNS:-.simbench/runs.pkl}
mkdir -p "$OUT"
filter() { grep --line-buffered -v "^Module\|^Warp\|^     \"\|^     /\|CUDA Toolkit\|Devices:\|Kernel cache"; }  # warp's start-up listing
case "$PHASE" in
profile)
  for skip in true false; do
    python benchmarks/bench_sim.py profile --inputs "$SIM_INPUTS" --device cuda --batches 64,256 --self on \
      --frames 3 --top 12 --set projection_skip=$skip 2>&1 | filter | tee "$OUT/profile_skip_$skip.txt" | grep -A12 "^=="
  done
  [ "${NEWTON:-1}" = 1 ] && python benchmarks/bench_newton.py --inputs "$NEWTON_RUNS" --scene tshirt/walk \
    --device cuda --batches 64 --self on,off --frames 40 2>&1 | filter | tee "$OUT/newton_b64.txt" ;;
paper-motion)
  (nvidia-smi --query-gpu=timestamp,utilization.gpu,memory.used --format=csv -l 10 > "$OUT/smi.csv" &)
  ( time timeout 585 python -m datagen.cli generate --preset paper-motion --batch-size 252 --out /tmp/pm.zarr \
      --device cuda ) > "$OUT/generate_pm.log" 2>&1
  echo "exit $?"; grep -v "^scene \|^Module\|^Warp" "$OUT/generate_pm.log" | tail -30
  grep "set-up of" "$OUT/generate_pm.log" ;;
compare)
  # SETS: space-separated variants of this tree, each a comma-separated list of SolverConfig KEY=VALUE
  # ("-": the defaults); BASE=none leaves the earlier tree out; TESTS=1 first runs the simulator's
  # CUDA-only tests (their output in $OUT/cuda_tests.txt)
  [ "${TESTS:-0}" = 1 ] && python -m pytest -q -p no:cacheprovider -k cuda tests/sim/test_launch_settings.py \
    tests/sim/test_projection_skip.py tests/sim/test_physics.py tests/sim/test_untangle.py 2>&1 | filter \
    > "$OUT/cuda_tests.txt"; [ -f "$OUT/cuda_tests.txt" ] && tail -3 "$OUT/cuda_tests.txt"
  trees=("${BASE:-.bench_base}"); [ "${BASE:-}" = none ] && trees=()
  for tree in "${trees[@]}"; do
    ( cd "$tree" && PYTHONPATH="$PWD:$PYTHONPATH" python benchmarks/bench_sim.py profile --inputs "$OLDPWD/$SIM_INPUTS" \
        --device cuda --batches ${BATCHES:-64,256} --self on --frames 3 --top 14 ) 2>&1 | filter \
      | tee "$OUT/profile_base.txt" | grep -A16 "^=="
  done
  for set in ${SETS:--}; do
    args=(); [ "$set" != - ] && for kv in ${set//,/ }; do args+=(--set "$kv"); done
    echo "### this tree, ${set}"
    python benchmarks/bench_sim.py profile --inputs "$SIM_INPUTS" --device cuda --batches ${BATCHES:-64,256} --self on \
      --frames 3 --top 14 "${args[@]}" 2>&1 | filter | tee "$OUT/profile_this_${set//[=,]/_}.txt" | grep -A16 "^=="
  done ;;
six)
  for set in ${SETS:--}; do  # as in compare: each a comma-separated list of KEY=VALUE, "-": the defaults
    args=(); [ "$set" != - ] && for kv in ${set//,/ }; do args+=(--set "$kv"); done
    echo "### six runs, ${set}"
    python benchmarks/bench_sim.py run-scenes --inputs "$RUNS" --device cuda "${args[@]}" 2>&1 | filter \
      | grep --line-buffered -v "frame [0-9]*/" | tee "$OUT/six_runs_${set//[=,]/_}.txt"
  done ;;
figures)
  W=${W:-/tmp/s25}; mkdir -p "$W"; : > "$W/progress"; rm -f "$W/done"  # a poll waits for this run, not an earlier one
  sets=(); opts=(); for kv in ${SET//,/ }; do sets+=(--set "$kv"); opts+=(--drape-option "$kv"); done  # SET: as in compare
  step() { echo "$(date +%T) $1 exit $2" >> "$W/progress"; }
  [ "${NEWTON:-1}" = 1 ] && { python benchmarks/bench_newton.py --inputs "$NEWTON_RUNS" --scene tshirt/walk --device cuda \
    --batches ${NEWTON_BATCHES:-64,256} --self ${NEWTON_SELF:-on,off} --frames 40 --check-filters \
    --newton-launch ${NEWTON_LAUNCH:-graph} --profile ${NEWTON_PROFILE:-12} "${opts[@]}" 2>&1 | filter > "$W/newton.txt"; step newton $?; }
  [ "${NEWTON:-1}" = 1 ] && [ "${NEWTON_PY_BATCHES:-64}" != none ] && { python benchmarks/bench_newton.py --inputs "$NEWTON_RUNS" \
    --scene tshirt/walk --device cuda --batches ${NEWTON_PY_BATCHES:-64} --self ${NEWTON_SELF:-on,off} --frames 40 \
    --solvers newton --newton-launch python 2>&1 | filter > "$W/newton_python.txt"; step newton-python $?; }
  python benchmarks/bench_sim.py run --inputs "$SIM_INPUTS" --device cuda --batches ${BATCHES:-1,16,64,256} --self on,off "${sets[@]}" 2>&1 \
    | filter > "$W/throughput.txt"; step throughput $?
  [ "${PROFILE:-}" ] && { python benchmarks/bench_sim.py profile --inputs "$SIM_INPUTS" --device cuda --batches "$PROFILE" \
    --self on --frames 3 --top 12 "${sets[@]}" 2>&1 | filter > "$W/profile.txt"; step profile $?; }
  [ "${SIX:-0}" = 1 ] && { python benchmarks/bench_sim.py run-scenes --inputs "$RUNS" --device cuda "${sets[@]}" 2>&1 | filter \
    | grep --line-buffered -v "frame [0-9]*/" > "$W/six_runs.txt"; step six $?; }
  if [ "${GNN_CACHE:-}" ]; then  # a DRAPE_CACHE_DIR with paper-gnn's bodies and garments (benchmarks/build_garment_cache.py)
    (nvidia-smi --query-gpu=timestamp,utilization.gpu,memory.used --format=csv -l 10 > "$W/smi_gnn.csv" &)
    gnn=(--preset paper-gnn)
    if [ "${SET:-}" ]; then  # the preset with SET's solver fields: a config file of its own
      python -m datagen.cli generate --preset paper-gnn --out /tmp/gnn.zarr --print-config | python -c '
import json, sys
from datagen.sim.settings import FLAT_NAMES
cfg = json.load(sys.stdin)
for kv in sys.argv[1].split(","):
    k, v = kv.split("=", 1)
    *groups, name = FLAT_NAMES.get(k, k).split(".")  # a flat name or group.field: its place in the groups
    table = cfg["simulation"]["solver"]
    for g in groups:
        table = table[g]
    table[name] = json.loads(v) if v[:1] in "0123456789-[{tf" else v
json.dump(cfg, sys.stdout, indent=1)' "$SET" > "$W/paper_gnn_set.yaml" && gnn=("$W/paper_gnn_set.yaml")
    fi
    ( time DRAPE_CACHE_DIR="$GNN_CACHE" timeout ${GNN_SECONDS:-585} python -m datagen.cli generate "${gnn[@]}" \
        --out /tmp/gnn.zarr --device cuda ) > "$W/generate_gnn.log" 2>&1; step paper-gnn $?
  fi
  touch "$W/done" ;;
poll)
  W=${W:-/tmp/s25}; t0=$SECONDS
  while [ ! -f "$W/done" ] && [ $((SECONDS - t0)) -lt "${WAIT:-540}" ]; do sleep 5; done
  cat "$W/progress"; for f in "$W"/newton.txt "$W"/newton_python.txt "$W"/throughput.txt "$W"/profile.txt "$W"/six_runs.txt "$W"/generate_gnn.log; do [ -f "$f" ] && { echo "== $f"; grep -v "frame [0-9]*/" "$f" | tail -${TAIL:-40}; }; done
  cp "$W"/*.txt "$W"/*.log "$W"/*.csv "$W/progress" "$OUT/" 2>/dev/null ;;
*) echo "PHASE must be profile, compare, paper-motion, six, figures or poll" >&2; exit 2 ;;
esac
