#!/bin/bash
# Issue 58's GPU check, one device session: the simulator before (62ea0bb, in _before/) and after
# (this tree) on the same card, one after the other: the six 300-frame runs, then drape beside
# Newton at 64 and 256 scenes with self-collision on and off; then `small` on the after tree.
#   PHASE=start: unpack warp and wheels, run everything under setsid into $W; PHASE=poll: wait, copy.
W=/tmp/g58; OUT=${OUT:-/tmp/o}
filter() { grep --line-buffered -v "^Module\|^Warp\|^     \"\|^     /\|CUDA Toolkit\|Devices:\|Kernel cache\|frame [0-9]*/"; }
step() { echo "$(date +%T) $1 exit $2" >> "$W/progress"; }
case "$PHASE" in
start)
  mkdir -p "$W"; : > "$W/progress"
  source .gpu/c/activate || exit 3
  python3 -m pip install -q --no-index --no-deps --no-compile --upgrade --target /tmp/site /root/stash/wheels/*.whl 2>&1 | grep -v "already exists"
  python3 -c "import warp, newton, zarr, trimesh; print('warp', warp.__version__, 'newton', newton.__version__)"
  nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv
  export PYTHONUNBUFFERED=1 ROOT=$PWD
  setsid bash -c '
    filter() { grep --line-buffered -v "^Module\|^Warp\|^     \"\|^     /\|CUDA Toolkit\|Devices:\|Kernel cache\|frame [0-9]*/"; }
    step() { echo "$(date +%T) $1 exit $2" >> '"$W"'/progress; }
    W='"$W"'
    cd $ROOT/_before && PYTHONPATH=$PWD:$PYTHONPATH python benchmarks/bench_sim.py run-scenes --inputs $ROOT/.simbench/runs.pkl --device cuda 2>&1 | filter > $W/six_before.txt; step six-before $?
    cd $ROOT && PYTHONPATH=$PWD:$PYTHONPATH python benchmarks/bench_sim.py run-scenes --inputs .simbench/runs.pkl --device cuda 2>&1 | filter > $W/six_after.txt; step six-after $?
    cd $ROOT && PYTHONPATH=$PWD:$PYTHONPATH python benchmarks/bench_newton.py --inputs .simbench/newton_runs.pkl --scene tshirt/walk --device cuda --batches 64,256 --self on,off --frames 40 --check-filters --newton-launch graph 2>&1 | filter > $W/newton_after.txt; step newton-after $?
    cd $ROOT/_before && PYTHONPATH=$PWD:$PYTHONPATH python benchmarks/bench_newton.py --inputs $ROOT/.simbench/newton_runs.pkl --scene tshirt/walk --device cuda --batches 64,256 --self on,off --frames 40 --solvers drape 2>&1 | filter > $W/newton_before_drape.txt; step newton-before-drape $?
    cd $ROOT && PYTHONPATH=$PWD:$PYTHONPATH python benchmarks/bench_newton.py --inputs .simbench/newton_runs.pkl --scene tshirt/walk --device cuda --batches 64,256 --self on,off --frames 40 --solvers drape 2>&1 | filter > $W/newton_after_drape.txt; step newton-after-drape $?
    if [ -d $ROOT/.gpucache_small ]; then
      cd $ROOT && ( time DRAPE_CACHE_DIR=$ROOT/.gpucache_small PYTHONPATH=$PWD:$PYTHONPATH timeout 420 python -m datagen.cli generate --preset small --out /tmp/small.zarr --device cuda ) > $W/generate_small.log 2>&1; step small $?
    fi
    touch $W/done' > "$W/driver.log" 2>&1 < /dev/null &
  sleep 2; echo started ;;
poll)
  t0=$SECONDS
  while [ ! -f "$W/done" ] && [ $((SECONDS - t0)) -lt "${WAIT:-540}" ]; do sleep 5; done
  cat "$W/progress"; for f in "$W"/*.txt "$W"/*.log; do [ -f "$f" ] && { echo "== $f"; grep -v "^scene \|frame [0-9]*/" "$f" | tail -${TAIL:-30}; }; done
  mkdir -p "$OUT"; tar czf "$OUT/g58.tar.gz" -C "$W" . ;;
esac
