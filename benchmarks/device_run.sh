#!/bin/bash
# drape's GPU benchmarks on a device machine, in named phases that each fit one command of at most ten
# minutes; a longer one runs in the background across commands (`start`, then `poll`).
#
#   bash benchmarks/device_run.sh PHASE             run PHASE now (its figures on stdout, its logs in $OUT)
#   bash benchmarks/device_run.sh start PHASE       run PHASE in a process session of its own (setsid: it outlives
#                                                    the command, not the machine) and return at once
#   bash benchmarks/device_run.sh poll              wait (WAIT s, default 540) for the phase `start`ed, then print its
#                                                    progress and logs and copy them to $OUT
#
# Phases (options are environment variables; `KEY=VALUE,KEY=VALUE` lists are SolverConfig fields; DEVICE=cpu
# with small inputs is a dry run of a phase on a CPU):
#   six       the six 300-frame runs (T-shirt, dress, pants x walk, dance_disco) at the production settings:
#             `python -m benchmarks sim run-scenes` on RUNS (default .simbench/runs.pkl), once per item of SETS
#             (space-separated, "-": the defaults). Per run: failure, crossings, frames inside, strain; ms per frame.
#             SAVE=1: each run's metrics and every 10th recorded frame in $OUT/six_<set>/ (strain-regions, crossing-regions).
#   figures   the throughput table and Newton side by side, one run after the other on an otherwise idle card:
#             `newton` at NEWTON_BATCHES (64,256), self-collision NEWTON_SELF (on,off), Newton's frame as a CUDA graph
#             (NEWTON_LAUNCH), each solver's top NEWTON_PROFILE kernels; Newton launched from Python at
#             NEWTON_PY_BATCHES (64; none: not); then `sim run` at BATCHES (1,16,64,256), self on and off. NEWTON=0:
#             no Newton; PROFILE=64,256: `sim profile` at those batches too; SIX=1: the six runs too; SET: SolverConfig
#             fields for every run; GNN_CACHE=DIR: `drape generate --preset paper-gnn` from that garment cache (made
#             by `python -m benchmarks garment-cache --preset paper-gnn`), stopped at GNN_SECONDS (585).
#             Inputs: SIM_INPUTS (.simbench/sim_inputs.npz, `sim prepare`), NEWTON_RUNS (.simbench/newton_runs.pkl,
#             `sim prepare-runs`). Run it with `start`: it takes longer than a command.
#   profile   `sim profile` (per kernel and per phase of a frame) at BATCHES (64,256), self-collision on, once per item
#             of SETS; with BASE=DIR first the same in an earlier tree (a copy of its datagen/ and benchmarks/, e.g.
#             `git archive REF datagen benchmarks | tar x -C .bench_base`): before and after on the same card.
#   small     `drape generate --preset small` (or GEN: a preset or config file) on the GPU under `time` (its figures: scenes passed, garment-frames/s end
#             to end), `drape validate`, `drape info`, then `python -m benchmarks garment-strain` on it; STORE
#             (/tmp/small.zarr). With `start` when the kernels are not compiled yet.
#   gnn       paper 000's GNN on STORE (made by `small` unless it is valid already): `drape train gnn` with CONFIG
#             (benchmarks/configs/gnn_small.yaml), `drape evaluate` on the test and validation splits, one test
#             sample predicted, the validation curves.
#   ddp       DDP training with torchrun on 1 and every GPU of the host (same global batch; WEAK=1: the same batch per
#             GPU), the N-GPU checkpoint resumed on one GPU; MODEL=gnn|garment, STORE, CONFIG
#             (benchmarks/configs/<MODEL>_ddp.yaml); the curves in $OUT/<MODEL>_ddp_curves.png.
#   pack      (here, not on the device) after ../shared/tools/gpu-warp/prepare: the wheels these phases need beside
#             warp (zarr, trimesh, ...) into .gpu/c/wheels, pinned to the versions installed here; RAY=1 also Ray,
#             split in two parts added to .gpu/a and .gpu/b (unpack on the host with
#             `cat /root/stash/raypart00 /root/stash/raypart01 | tar xJ -C /tmp/site`).
#
# On a lent device machine (../shared/tools/gpu-warp/README.md, /work/.library/device/README.md): upload .gpu/a
# and .gpu/b once, then every call carries .gpu/c (and .simbench for the inputs) and starts with
# `source .gpu/c/activate &&`; figures and logs go to $OUT (only 8 files come back: logs are packed where many).
# Examples:
#   OUT=$OUT bash benchmarks/device_run.sh six
#   OUT=$OUT bash benchmarks/device_run.sh start figures; then OUT=$OUT bash benchmarks/device_run.sh poll (repeat)
#   OUT=$OUT BASE=.bench_base SETS="- sweep_groups=1" bash benchmarks/device_run.sh profile
#   OUT=$OUT bash benchmarks/device_run.sh start small; then OUT=$OUT bash benchmarks/device_run.sh poll
set -o pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
cd "$ROOT" || exit 2
OUT=${OUT:-/tmp/device-out}; W=${W:-/tmp/device-run}; mkdir -p "$OUT" "$W"
RUNS=${RUNS:-.simbench/runs.pkl}; SIM_INPUTS=${SIM_INPUTS:-.simbench/sim_inputs.npz}
NEWTON_RUNS=${NEWTON_RUNS:-.simbench/newton_runs.pkl}; STORE=${STORE:-/tmp/small.zarr}
DEVICE=${DEVICE:-cuda}  # cpu: a dry run of a phase on a CPU (small inputs: RUNS, SIM_INPUTS, GEN, BATCHES)
GEN=${GEN:---preset small}  # what `small` and `gnn` generate: a preset, or a config file
D="python -m datagen.cli"
B="python -m benchmarks"
filter() { grep --line-buffered -v "^Module\|^Warp\|^     \"\|^     /\|CUDA Toolkit\|Devices:\|Kernel cache"; }  # warp's start-up listing
sets_args() { args=(); [ "$1" != - ] && for kv in ${1//,/ }; do args+=(--set "$kv"); done; }  # "-" or k=v,k=v -> --set ...
absolute() { case $1 in /*) echo "$1" ;; *) echo "$ROOT/$1" ;; esac; }
step() { echo "$(date +%T) $1 exit $2" >> "$W/progress"; }

# `sim profile` in TREE (this one, or an earlier copy that predates `python -m benchmarks`: its own script)
profile_in() {
  local tree=$1; shift
  if [ -f "$tree/benchmarks/__main__.py" ]; then
    (cd "$tree" && PYTHONPATH="$PWD:$PYTHONPATH" python -m benchmarks sim profile "$@")
  else
    (cd "$tree" && PYTHONPATH="$PWD:$PYTHONPATH" python -m benchmarks sim profile "$@")
  fi
}

phase="${1:?a phase: six, figures, profile, small, gnn, ddp, pack, start PHASE or poll}"
case "$phase" in
start)
  [ -n "$2" ] || { echo "start which phase?" >&2; exit 2; }
  : > "$W/progress"; rm -f "$W/done"  # a poll waits for this run, not an earlier one
  OUT="$W" setsid nohup bash "$0" "$2" > "$W/$2.log" 2>&1 < /dev/null &
  echo "started $2 in the background (pid $!); its log: $W/$2.log; then: bash $0 poll" ;;
poll)
  t0=$SECONDS
  while [ ! -f "$W/done" ] && [ $((SECONDS - t0)) -lt "${WAIT:-540}" ]; do sleep 5; done
  [ -f "$W/done" ] && echo "done" || echo "still running after ${WAIT:-540} s"
  cat "$W/progress"
  for f in "$W"/*.txt "$W"/*.log; do [ -f "$f" ] && { echo "== $f"; grep -v "frame [0-9]*/\|it/s\]$" "$f" | filter | tail -"${TAIL:-40}"; }; done
  tar czf "$OUT/device_run.tgz" -C "$W" --exclude='*.zarr' . 2>/dev/null; ls -la "$OUT" ;;
six)
  for set in ${SETS:--}; do
    sets_args "$set"
    echo "### six runs, ${set}"
    [ "${SAVE:-0}" = 1 ] && args+=(--out-dir "$OUT/six_${set//[=,]/_}")  # for strain-regions, crossing-regions
    $B sim run-scenes --inputs "$RUNS" --device "$DEVICE" "${args[@]}" 2>&1 | filter \
      | grep --line-buffered -v "frame [0-9]*/" | tee "$OUT/six_runs_${set//[=,]/_}.txt"
    step "six $set" $?
  done
  touch "$W/done" ;;
figures)
  sets=(); opts=(); for kv in ${SET//,/ }; do sets+=(--set "$kv"); opts+=(--drape-option "$kv"); done
  if [ "${NEWTON:-1}" = 1 ]; then
    $B newton --inputs "$NEWTON_RUNS" --scene tshirt/walk --device "$DEVICE" --batches "${NEWTON_BATCHES:-64,256}" \
      --self "${NEWTON_SELF:-on,off}" --frames 40 --check-filters --newton-launch "${NEWTON_LAUNCH:-graph}" \
      --profile "${NEWTON_PROFILE:-12}" "${opts[@]}" 2>&1 | filter > "$OUT/newton.txt"; step newton $?
    if [ "${NEWTON_PY_BATCHES:-64}" != none ]; then
      $B newton --inputs "$NEWTON_RUNS" --scene tshirt/walk --device "$DEVICE" --batches "${NEWTON_PY_BATCHES:-64}" \
        --self "${NEWTON_SELF:-on,off}" --frames 40 --solvers newton --newton-launch python 2>&1 | filter \
        > "$OUT/newton_python.txt"; step newton-python $?
    fi
  fi
  $B sim run --inputs "$SIM_INPUTS" --device "$DEVICE" --batches "${BATCHES:-1,16,64,256}" --self on,off "${sets[@]}" 2>&1 \
    | filter > "$OUT/throughput.txt"; step throughput $?
  if [ -n "${PROFILE:-}" ]; then
    $B sim profile --inputs "$SIM_INPUTS" --device "$DEVICE" --batches "$PROFILE" --self on --frames 3 --top 12 "${sets[@]}" \
      2>&1 | filter > "$OUT/profile.txt"; step profile $?
  fi
  if [ "${SIX:-0}" = 1 ]; then
    $B sim run-scenes --inputs "$RUNS" --device "$DEVICE" "${sets[@]}" 2>&1 | filter | grep --line-buffered -v "frame [0-9]*/" \
      > "$OUT/six_runs.txt"; step six $?
  fi
  if [ -n "${GNN_CACHE:-}" ]; then
    (nvidia-smi --query-gpu=timestamp,utilization.gpu,memory.used --format=csv -l 10 > "$OUT/smi_gnn.csv" &)
    gnn=(--preset paper-gnn)
    if [ -n "${SET:-}" ]; then  # the preset with SET's solver fields: a config file of its own
      $D generate --preset paper-gnn --out /tmp/gnn.zarr --print-config | python -c '
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
json.dump(cfg, sys.stdout, indent=1)' "$SET" > "$OUT/paper_gnn_set.yaml" && gnn=("$OUT/paper_gnn_set.yaml")
    fi
    ( time DRAPE_CACHE_DIR="$GNN_CACHE" timeout "${GNN_SECONDS:-585}" $D generate "${gnn[@]}" --out /tmp/gnn.zarr \
        --device "$DEVICE" ) > "$OUT/generate_gnn.log" 2>&1; step paper-gnn $?
  fi
  touch "$W/done" ;;
profile)
  if [ -n "${BASE:-}" ]; then
    echo "### the earlier tree $BASE"
    profile_in "$BASE" --inputs "$(absolute "$SIM_INPUTS")" --device "$DEVICE" --batches "${BATCHES:-64,256}" --self on --frames 3 \
      --top 14 2>&1 | filter | tee "$OUT/profile_base.txt" | grep -A16 "^=="
  fi
  for set in ${SETS:--}; do
    sets_args "$set"
    echo "### this tree, ${set}"
    profile_in "$ROOT" --inputs "$(absolute "$SIM_INPUTS")" --device "$DEVICE" --batches "${BATCHES:-64,256}" --self on --frames 3 \
      --top 14 "${args[@]}" 2>&1 | filter | tee "$OUT/profile_this_${set//[=,]/_}.txt" | grep -A16 "^=="
  done
  touch "$W/done" ;;
small)
  ( time $D generate $GEN --out "$STORE" --device "$DEVICE" ) > "$OUT/generate_small.log" 2>&1; step generate $?
  filter < "$OUT/generate_small.log" | grep -v "^scene \|it/s\]$" | tail -n 14
  $D validate "$STORE" 2>&1 | tee "$OUT/validate_small.txt"
  $D info "$STORE" > "$OUT/info_small.txt" 2>&1
  $B garment-strain "$STORE" 2>&1 | filter | tee "$OUT/small_strain.txt"; step strain $?
  touch "$W/done" ;;
gnn)
  RUN=${RUN:-/tmp/runs/gnn}; CONFIG=${CONFIG:-benchmarks/configs/gnn_small.yaml}
  if ! $D validate "$STORE" > /dev/null 2>&1; then
    $D generate $GEN --out "$STORE" --device "$DEVICE" > "$OUT/generate.log" 2>&1
  fi
  $D info "$STORE" > "$OUT/info.txt" 2>&1
  $D train gnn --data "$STORE" --out "$RUN" --config "$CONFIG" --device "$DEVICE" --force > "$OUT/train.log" 2>&1; step train $?
  cp "$RUN/run.json" "$OUT/"; cp "$RUN/train_summary.json" "$OUT/" 2>/dev/null
  $D evaluate "$RUN" --split test --json "$OUT/eval_test.json" --device "$DEVICE" > "$OUT/eval_test.log" 2>&1
  $D evaluate "$RUN" --split val --max-frames 60 --json "$OUT/eval_val.json" --device "$DEVICE" > "$OUT/eval_val.log" 2>&1
  SAMPLE=$(python -c "from datagen.store import open_store; print(int(open_store('$STORE').split('test', include_failed=False)[0]))")
  $D predict "$RUN" --data "$STORE" --sample "$SAMPLE" --out "$OUT/pred.usd" > "$OUT/predict.log" 2>&1
  python -c "
from training.loop import read_metrics
for k in ('train/loss_epoch', 'val/coarse_mm', 'val/detail_mm'):
    print(k, {e: round(v, 3) for e, v in read_metrics('$RUN', k).items()})" | tee "$OUT/curves.txt"
  tail -2 "$OUT/train.log"; filter < "$OUT/eval_test.log" | tail -12
  touch "$W/done" ;;
ddp)
  export NCCL_NVLS_ENABLE=0 TORCH_SYMM_MEM_DISABLE_MULTICAST=1 NVSHMEM_DISABLE_NVLS=1  # NVLink multicast stays off
  MODEL=${MODEL:-gnn}; CONFIG=${CONFIG:-benchmarks/configs/${MODEL}_ddp.yaml}
  VAL=$([ "$MODEL" = gnn ] && echo val/detail_mm || echo val/vertex_mm)
  NGPU=$(python -c "import torch; print(torch.cuda.device_count())")
  for N in $NGPU 1; do
    CFG=$CONFIG
    if [ "${WEAK:-0}" = 1 ] && [ "$N" -gt 1 ]; then
      CFG=$W/weak$N.yaml
      python -c "import yaml; c = yaml.safe_load(open('$CONFIG')); c['batch_size'] *= $N
c.update({'max_batch_size': c['max_batch_size'] * $N} if 'max_batch_size' in c else {}); yaml.safe_dump(c, open('$CFG', 'w'))"
    fi
    torchrun --standalone --nproc-per-node "$N" -m datagen.cli train "$MODEL" --data "$STORE" --out "$W/runs/$MODEL$N" \
      --config "$CFG" --device "$DEVICE" --force > "$OUT/${MODEL}_ddp$N.log" 2>&1; step "ddp $N" $?
    cp "$W/runs/$MODEL$N/train_summary.json" "$OUT/${MODEL}_summary_ddp$N.json"
    if [ "$N" -gt 1 ]; then  # the N-GPU checkpoint resumed on one GPU for one more epoch
      EPOCHS=$(python -c "import json; print(json.load(open('$W/runs/$MODEL$N/run.json'))['config']['epochs'] + 1)")
      $D train "$MODEL" --data "$STORE" --out "$W/runs/$MODEL$N" --config "$CFG" --device "$DEVICE" --resume \
        --epochs "$EPOCHS" > "$OUT/${MODEL}_resume_ddp${N}_on1.log" 2>&1; step "resume on 1" $?
    fi
  done
  python - "$NGPU" "$OUT" "$MODEL" "$VAL" "$W/runs" <<'PY' | tee "$OUT/${MODEL}_ddp.txt"
import json, sys
import matplotlib; matplotlib.use("Agg")
import matplotlib.pyplot as plt
from training.loop import read_metrics
n, out, model, val, runs = int(sys.argv[1]), sys.argv[2], sys.argv[3], sys.argv[4], sys.argv[5]
rates = {}
fig, ax = plt.subplots(1, 2, figsize=(10, 4))
for k in sorted({1, n}):
    s = json.load(open(f"{out}/{model}_summary_ddp{k}.json"))
    r = s["train_samples_per_second"]
    later = sorted(r[1:] if len(r) > 1 else r)
    rates[k] = later[len(later) // 2]
    print(f"N={k}: world {s['world_size']}, epochs {s['epochs']}, samples/s per epoch {[round(x, 1) for x in r]}, "
          f"median after the first {rates[k]:.1f}; best monitored validation value {s['best']:.4g}")
    for a, key in zip(ax, ("train/loss_epoch", val)):
        m = read_metrics(f"{runs}/{model}{k}", key)
        print(f"  {key} per epoch {[round(v, 4) for v in m.values()]}")
        a.plot(list(m), list(m.values()), "o-", label=f"{k} GPU(s)")
        a.set_title(key); a.set_xlabel("epoch"); a.legend()
if n > 1:
    print(f"scaling: {rates[n] / rates[1]:.2f}x on {n} GPUs, efficiency {rates[n] / rates[1] / n:.0%}")
    print(f"resumed on 1 GPU: epochs {list(read_metrics(f'{runs}/{model}{n}', 'train/loss_epoch'))}")
fig.suptitle(f"{model}: 1 and {n} GPUs"); fig.tight_layout(); fig.savefig(f"{out}/{model}_ddp_curves.png", dpi=100)
PY
  touch "$W/done" ;;
pack)
  set -eu
  [ -x "$ROOT/.venv/bin/python" ] && export PATH="$ROOT/.venv/bin:$PATH"
  [ -d "$ROOT/.gpu/c/wheels" ] || { echo "run ../shared/tools/gpu-warp/prepare first" >&2; exit 2; }
  dl() {  # binary wheels for the host's Python 3.12
    python3 -m pip download -q --no-deps --only-binary=:all: --python-version 3.12 --implementation cp \
      --platform manylinux_2_28_x86_64 --platform manylinux_2_17_x86_64 --platform manylinux2014_x86_64 -d "$1" "${@:2}"
  }
  pin() {  # NAME==VERSION as installed here (the GPU host then runs what the tests ran), else NAME
    for n in "$@"; do
      v=$(python3 -c "import importlib.metadata as m; print(m.version('$n'))" 2>/dev/null) && echo "$n==$v" || echo "$n"
    done
  }
  dl "$ROOT/.gpu/c/wheels" $(pin zarr numcodecs donfig google-crc32c trimesh rtree tensorboardX jsonschema \
    jsonschema-specifications referencing rpds-py pytest pluggy iniconfig)
  if [ "${RAY:-0}" = 1 ]; then  # Ray core only: its Java jars, RLlib and dashboard client left out
    tmp=$(mktemp -d)
    dl "$tmp" $(pin ray)
    mkdir "$tmp/site" && (cd "$tmp/site" && unzip -q "$tmp"/ray-*.whl && rm -rf ray/jars ray/rllib ray/dashboard/client)
    tar cf - -C "$tmp/site" . | xz -T0 -6 > "$tmp/ray.tar.xz"
    split -n 2 -d "$tmp/ray.tar.xz" "$tmp/raypart"
    cp "$tmp/raypart00" "$ROOT/.gpu/a/"; cp "$tmp/raypart01" "$ROOT/.gpu/b/"
    rm -rf "$tmp"
  fi
  du -sh "$ROOT/.gpu/a" "$ROOT/.gpu/b" "$ROOT/.gpu/c" ;;
*) echo "unknown phase $phase: six, figures, profile, small, gnn, ddp, pack, start PHASE or poll" >&2; exit 2 ;;
esac
