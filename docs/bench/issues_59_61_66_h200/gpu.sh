#!/bin/bash
# The seventh session's driver (65d855c against c923ff9): git show dc58b64:docs/bench/issues_59_61_66_h200/gpu_s7.sh
# Issue 66's leave-one-out runs (DRAPE_V66_OFF, a patched copy in _v66/): the same phases with generate --preset small-shell only.
# Issues 59, 61, 66 on one GPU (eighth session; before = dc58b64 in _before/), one device session: the six 300-frame runs (shells; pattern garments),
# drape beside Newton, the same drape-alone figures in the tree before (c923ff9, in _before/), and
# `small` with shells and with pattern garments. PHASE=start: run it all under setsid into $W;
# PHASE=poll: wait, print, copy. Inputs in /root/stash/data (a call carrying .simbench, .gpucache_small, _before).
W=/tmp/g9; OUT=${OUT:-/tmp/o}; D=/root/stash/data
case "$PHASE" in
stash)
  mkdir -p $D && cp -r .simbench .gpucache_small _before $D/ && du -sh $D/* ;;
start)
  mkdir -p "$W"; : > "$W/progress"
  source .gpu/c/activate || exit 3
  python3 -m pip install -q --no-index --no-deps --no-compile --upgrade --target /tmp/site /root/stash/wheels/*.whl 2>&1 | grep -v "already exists"
  python3 -c "import warp, newton, zarr, trimesh, scipy; print('warp', warp.__version__, 'newton', newton.__version__, 'scipy', scipy.__version__)"
  nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv
  export PYTHONUNBUFFERED=1 ROOT=$PWD
  setsid bash -c '
    filter() { grep --line-buffered -v "^Module\|^Warp\|^     \"\|^     /\|CUDA Toolkit\|Devices:\|Kernel cache\|frame [0-9]*/"; }
    step() { echo "$(date +%T) $1 exit $2" >> '"$W"'/progress; }
    W='"$W"'; D='"$D"'
    cd $ROOT && PYTHONPATH=$PWD:$PYTHONPATH python -m benchmarks sim run-scenes --inputs $D/.simbench/runs.pkl --device cuda 2>&1 | filter > $W/six_after.txt; step six-after $?
    cd $ROOT && ( time DRAPE_CACHE_DIR=$D/.gpucache_small PYTHONPATH=$PWD:$PYTHONPATH timeout 500 python -m datagen.cli generate --preset small-shell --out /tmp/small.zarr --device cuda ) > $W/generate_small.log 2>&1; step small $?
    cd $ROOT && PYTHONPATH=$PWD:$PYTHONPATH python -m datagen.cli validate /tmp/small.zarr > $W/validate_small.txt 2>&1; step validate-small $?
    cd $ROOT && PYTHONPATH=$PWD:$PYTHONPATH python -m benchmarks newton --inputs $D/.simbench/newton_runs.pkl --scene tshirt/walk --device cuda --batches 64,256 --self on,off --frames 40 --check-filters --newton-launch graph 2>&1 | filter > $W/newton_after.txt; step newton-after $?
    cd $D/_before && PYTHONPATH=$PWD:$PYTHONPATH python -m benchmarks newton --inputs $D/.simbench/newton_runs.pkl --scene tshirt/walk --device cuda --batches 64,256 --self on,off --frames 40 --solvers drape 2>&1 | filter > $W/newton_before_drape.txt; step newton-before-drape $?
    cd $D/_before && PYTHONPATH=$PWD:$PYTHONPATH python -m benchmarks sim run-scenes --inputs $D/.simbench/runs.pkl --device cuda 2>&1 | filter > $W/six_before.txt; step six-before $?
    [ -f $D/.simbench/pattern_runs3.pkl ] && cd $ROOT && PYTHONPATH=$PWD:$PYTHONPATH python -m benchmarks sim run-scenes --inputs $D/.simbench/pattern_runs3.pkl --device cuda 2>&1 | filter > $W/six_pattern.txt; step six-pattern $?
    cd $ROOT && ( time DRAPE_CACHE_DIR=$D/.gpucache_small PYTHONPATH=$PWD:$PYTHONPATH timeout 900 python -m datagen.cli generate --preset small-pattern --out /tmp/small_pattern.zarr --device cuda ) > $W/generate_small_pattern.log 2>&1; step small-pattern $?
    cd $ROOT && PYTHONPATH=$PWD:$PYTHONPATH python -m datagen.cli validate /tmp/small_pattern.zarr > $W/validate_small_pattern.txt 2>&1; step validate-small-pattern $?
    cd $ROOT && PYTHONPATH=$PWD:$PYTHONPATH python -m datagen.cli info /tmp/small_pattern.zarr > $W/info_small_pattern.txt 2>&1; step info-small-pattern $?
    touch $W/done' > "$W/driver.log" 2>&1 < /dev/null &
  sleep 2; echo started ;;
poll)
  t0=$SECONDS
  while [ ! -f "$W/done" ] && [ $((SECONDS - t0)) -lt "${WAIT:-540}" ]; do sleep 5; done
  cat "$W/progress"; for f in "$W"/*.txt "$W"/*.log; do [ -f "$f" ] && { echo "== $f"; grep -v "^scene \|frame [0-9]*/\|it/s\]$" "$f" | tail -${TAIL:-12}; }; done
  mkdir -p "$OUT"; tar czf "$OUT/g9.tar.gz" -C "$W" . ;;
esac
