"""GPU checks for issue 58 (run on the device from the repository root):
python out/gpu_check/gpu_check.py checks            # the CUDA tests of tests/training (after)
python out/gpu_check/gpu_check.py speed             # training steps/s, motion (graphed, eager) and GNN
"""
import json
import sys
import time

import numpy as np
import torch


def checks():
    import pytest

    import tests.training.test_garment as tga
    import tests.training.test_gnn as tg
    import tests.training.test_motion as tm

    with pytest.MonkeyPatch.context() as mp:
        tm.test_the_graphed_training_step_gives_the_eager_gradients(mp)
    print("motion graphed step == eager: ok", flush=True)
    for pb in (False, True):
        tg.test_a_captured_prediction_replays_what_eager_gives(pb)
    print("gnn captured prediction == eager: ok", flush=True)
    tga.test_greedy_decoding_replayed_as_a_cuda_graph_equals_plain_decoding()
    print("garment graphed decoding == plain: ok", flush=True)


def _clock(warmup):
    import pytorch_lightning as pl

    class Clock(pl.Callback):
        t0 = t1 = 0.0
        samples = 0
        losses = []

        def on_train_batch_start(self, trainer, pl_module, batch, batch_idx):
            if trainer.global_step == warmup:
                torch.cuda.synchronize()
                self.t0 = time.perf_counter()

        def on_train_batch_end(self, trainer, pl_module, outputs, batch, batch_idx):
            loss = outputs["loss"] if isinstance(outputs, dict) else outputs
            self.losses.append(float(loss))
            if trainer.global_step > warmup:
                n = getattr(batch, "num_graphs", None)
                self.samples += int(n) if n else int(batch["label"].shape[0])
                torch.cuda.synchronize()
                self.t1 = time.perf_counter()
    return Clock()


def _fit(module, loader, precision, steps, warmup):
    import warnings

    import pytorch_lightning as pl

    configure = module.configure_optimizers
    module.configure_optimizers = lambda: (lambda c: c["optimizer"] if isinstance(c, dict) else c)(configure())
    clock = _clock(warmup)
    trainer = pl.Trainer(accelerator="gpu", devices=1, precision=precision, max_steps=warmup + steps, max_epochs=-1,
                         limit_val_batches=0, num_sanity_val_steps=0, logger=False, enable_checkpointing=False,
                         enable_progress_bar=False, enable_model_summary=False, gradient_clip_val=1.0,
                         callbacks=[clock])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        trainer.fit(module, loader)
    return clock.samples / (clock.t1 - clock.t0), clock.losses


def speed(label):
    import pytorch_lightning as pl
    from torch_geometric.loader import DataLoader as GraphLoader

    from tests.training.grids import grid_frame
    from tests.training.test_motion import synthetic_batch
    from training.gnn.module import GNNModule
    from training.motion.config import MotionConfig
    from training.motion.module import MotionModule

    rows = {}
    body, batch = synthetic_batch(400, 5, "cpu")
    ds = [{k: v[i] for k, v in batch.items()} for i in range(400)]
    for graph in (True, False):
        for precision in ("bf16-mixed", "32"):
            pl.seed_everything(0, verbose=False)
            cfg = MotionConfig(batch_size=20, cuda_graph=graph).as_dict()
            m = MotionModule(cfg, 5, body, np.zeros((1, 10)))
            loader = torch.utils.data.DataLoader(ds, batch_size=20, shuffle=True, drop_last=True,
                                                 generator=torch.Generator().manual_seed(0))
            rate, losses = _fit(m, loader, precision, 60, 10)
            rows[f"motion graph={graph} {precision}"] = {"segments_per_s": rate, "loss_first": losses[0],
                                                         "loss_last": losses[-1]}
            print(label, f"motion cuda_graph={graph} {precision}: {rate:.1f} segments/s, loss {losses[0]:.4f} -> "
                  f"{losses[-1]:.4f}", flush=True)
    frames = [grid_frame(900, seed=k) for k in range(40)]
    for precision in ("bf16-mixed", "32"):
        pl.seed_everything(0, verbose=False)
        m = GNNModule({"seed": 0, "epochs": 40, "batch_size": 4, "lr": 1e-3, "lr_factor": 0.5, "lr_patience": 4,
                       "early_stop_patience": 10, "workers": 0, "precision": precision, "ablation": "full",
                       "target_scale": 100.0, "max_train_frames": None, "max_val_frames": 256, "epoch_frames": None,
                       "max_minutes": None}, 85)
        rate, losses = _fit(m, GraphLoader(frames, batch_size=4, shuffle=True), precision, 40, 5)
        rows[f"gnn {precision}"] = {"frames_per_s": rate, "loss_first": losses[0], "loss_last": losses[-1]}
        print(label, f"gnn {precision}: {rate:.1f} frames/s, loss {losses[0]:.4f} -> {losses[-1]:.4f}", flush=True)
    print(label, json.dumps(rows))


if __name__ == "__main__":
    sys.path.insert(0, ".")
    {"checks": checks, "speed": lambda: speed(sys.argv[2] if len(sys.argv) > 2 else "")}[sys.argv[1]]()
