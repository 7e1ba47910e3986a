#!/bin/bash
# DDP training with torchrun on 1 and N GPUs of one host (same global batch), then the N-GPU run's
# checkpoint resumed on one GPU for one more epoch; the loss curves on one plot. Figures go to $OUT.
#   OUT=/tmp/out STORE=/tmp/local1.zarr [MODEL=gnn|garment] [WEAK=1] bash benchmarks/multigpu_train.sh [CONFIG]
# MODEL: paper 000's GNN (default; config benchmarks/configs/gnn_ddp.yaml) or paper 001's garment
# regressor (benchmarks/configs/garment_ddp.yaml, on a store where its template is in every split,
# e.g. one made from benchmarks/configs/regressor_store.yaml).
# WEAK=1: the same batch per GPU instead (the N-GPU run's global batch is N times the config's):
# throughput scaling when one GPU's step is latency-bound (2026-11-25: 116 -> 102 samples/s on
# 2 H100s at the same global batch of 16). The resume comes first after the N-GPU run, so that it
# fits one 10-minute command.
set -o pipefail
export NCCL_NVLS_ENABLE=0 TORCH_SYMM_MEM_DISABLE_MULTICAST=1 NVSHMEM_DISABLE_NVLS=1
OUT=${OUT:-/tmp/mg-out}; STORE=${STORE:-/tmp/local1.zarr}; MODEL=${MODEL:-gnn}
CONFIG=${1:-benchmarks/configs/${MODEL}_ddp.yaml}
VAL=$([ "$MODEL" = gnn ] && echo val/detail_mm || echo val/vertex_mm)
mkdir -p "$OUT"
NGPU=$(python -c "import torch; print(torch.cuda.device_count())")
for N in $NGPU 1; do
  CFG=$CONFIG
  if [ "${WEAK:-0}" = "1" ] && [ $N -gt 1 ]; then
    CFG=/tmp/weak$N.yaml
    python -c "import yaml,sys; c=yaml.safe_load(open('$CONFIG')); c['batch_size']*=$N; c.update({'max_batch_size': c['max_batch_size']*$N} if 'max_batch_size' in c else {}); yaml.safe_dump(c, open('$CFG','w'))"
  fi
  torchrun --standalone --nproc-per-node $N -m datagen.cli train $MODEL --data "$STORE" --out /tmp/runs/$MODEL$N \
    --config "$CFG" --device cuda --force > "$OUT/${MODEL}_ddp$N.log" 2>&1
  cp /tmp/runs/$MODEL$N/train_summary.json "$OUT/${MODEL}_summary_ddp$N.json"
  if [ $N -gt 1 ]; then  # the N-GPU checkpoint resumed on one GPU for one more epoch
    EPOCHS=$(python -c "import json; print(json.load(open('/tmp/runs/$MODEL$N/run.json'))['config']['epochs'] + 1)")
    python -m datagen.cli train $MODEL --data "$STORE" --out /tmp/runs/$MODEL$N --config "$CFG" --device cuda --resume \
      --epochs $EPOCHS > "$OUT/${MODEL}_resume_ddp${N}_on1.log" 2>&1
  fi
done
python - "$NGPU" "$OUT" "$MODEL" "$VAL" <<'PY' | tee "$OUT/${MODEL}_ddp.txt"
import json, sys
from training.loop import read_metrics
n, out, model, val = int(sys.argv[1]), sys.argv[2], sys.argv[3], sys.argv[4]
rates = {}
for k in sorted({1, n}):
    s = json.load(open(f"{out}/{model}_summary_ddp{k}.json"))
    r = s["train_samples_per_second"]
    rates[k] = sorted(r[1:] if len(r) > 1 else r)[len(r[1:] if len(r) > 1 else r) // 2]
    print(f"N={k}: world {s['world_size']}, epochs {s['epochs']}, samples/s per epoch {[round(x, 1) for x in r]}, "
          f"median after the first {rates[k]:.1f}; best monitored validation value {s['best']:.4g}")
    print(f"  train loss per epoch {[round(v, 4) for v in read_metrics(f'/tmp/runs/{model}{k}', 'train/loss_epoch').values()]}")
    print(f"  {val} per epoch {[round(v, 2) for v in read_metrics(f'/tmp/runs/{model}{k}', val).values()]}")
if n > 1:
    print(f"scaling: {rates[n] / rates[1]:.2f}x on {n} GPUs, efficiency {rates[n] / rates[1] / n:.0%}")
print(f"resumed on 1 GPU: epochs {list(read_metrics(f'/tmp/runs/{model}{n}', 'train/loss_epoch'))}")
PY
python - "$OUT" "$NGPU" "$MODEL" "$VAL" <<'PY'
import sys
import matplotlib; matplotlib.use("Agg")
import matplotlib.pyplot as plt
from training.loop import read_metrics
out, n, model, val = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4]
fig, ax = plt.subplots(1, 2, figsize=(10, 4))
for k in sorted({1, n}):
    for a, key in zip(ax, ("train/loss_epoch", val)):
        m = read_metrics(f"/tmp/runs/{model}{k}", key)
        a.plot(list(m), list(m.values()), "o-", label=f"{k} GPU(s)")
        a.set_title(key); a.set_xlabel("epoch"); a.legend()
fig.suptitle(f"{model}: 1 and {n} GPUs"); fig.tight_layout(); fig.savefig(f"{out}/{model}_ddp_curves.png", dpi=100)
PY
tail -3 "$OUT/${MODEL}_resume_ddp${NGPU}_on1.log"
