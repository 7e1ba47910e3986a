#!/bin/bash
# Issue 25's candidate sweep setting on a GPU in one command (docs/simulator.md, "How many sweeps"):
# the six 300-frame runs (T-shirt, dress, pants x walk, dance_disco) at the production settings, with
# chebyshev_contacts=false, and with it at 10 sweeps a substep (three processes side by side, so their
# ms per frame are not speed figures), then Newton's VBD beside drape at 64 scenes (production, then the
# two candidates, drape alone), the speed figures.
#   OUT=/tmp/o RUNS=.simbench/runs.pkl NEWTON_RUNS=.simbench/newton_runs.pkl bash benchmarks/sweeps_gpu_run.sh
# (the two pickles from `bench_sim.py prepare-runs`: see docs/simulator.md)
set -o pipefail
OUT=${OUT:-/tmp/sweeps-out}; RUNS=${RUNS:-.simbench/runs.pkl}; NEWTON_RUNS=${NEWTON_RUNS:-.simbench/newton_runs.pkl}
BATCHES=${BATCHES:-64}; FRAMES=${FRAMES:-60}
mkdir -p "$OUT"
filter() { grep --line-buffered -v "^Module\|^Warp\|^   \|CUDA Toolkit\|Devices:\|Kernel cache"; }
six() {
  local name=$1; shift
  python benchmarks/bench_sim.py run-scenes --inputs "$RUNS" --device cuda "$@" 2>&1 | filter > "$OUT/six_$name.txt"
}
six production &
six contacts_off --set chebyshev_contacts=false &
six contacts_off_10 --set chebyshev_contacts=false --set iterations=10 &
wait
for n in production contacts_off contacts_off_10; do
  echo "== six runs, $n"
  python - "$OUT/six_$n.txt" <<'PY'
import json, sys
for line in open(sys.argv[1]):
    name, sep, rest = line.partition(": {")
    if sep and "/" in name:
        m = json.loads("{" + rest)
        print(f"  {name:20s} {m['failure'] or 'pass':55.55s} crossings max {m['self_intersections_max']:3d}  "
              f"frames inside {m['frames_with_penetration']:3d} (deepest {m['penetration_depth_max_mm']:.2f} mm)  "
              f"strain p99 {100 * m['strain_p99']:.1f} %  max {100 * m['stretch_max']:.0f} %")
    elif "ms per batch frame" in line:
        print("  " + line.strip())
PY
done
nw() {
  local name=$1; shift
  python benchmarks/bench_newton.py --inputs "$NEWTON_RUNS" --scene tshirt/walk --device cuda --batches "$BATCHES" \
    --self on,off --frames "$FRAMES" "$@" 2>&1 | filter | tee "$OUT/newton_$name.txt"
}
nw production
nw contacts_off --solvers drape --drape-option chebyshev_contacts=false
nw contacts_off_10 --solvers drape --drape-option chebyshev_contacts=false --drape-option iterations=10
