"""The one runner of drape's benchmarks: ``python -m benchmarks CASE [ARGS]``, ``python -m benchmarks --list``.

A case is a record (:class:`Case`): its name on the command line, the module that runs it and one line
on what it prints. The module is imported only when its case runs (``--list`` imports none of them), so
a case may need what another lacks (a GPU, newton, a store). Every case module has
``main(argv=None)``: it parses ``argv`` (the arguments after the case's name) and prints its figures;
its exit status is what ``main`` returns (``None``: 0). Cases written as :class:`~benchmarks.common.Benchmark`
(setup, run, report) get that ``main`` from the base class.

Run from the repository's root (``benchmarks`` is not part of the installed wheel).
"""

from __future__ import annotations

import argparse
import importlib
import sys
from dataclasses import dataclass


@dataclass(frozen=True, kw_only=True)
class Case:
    """One benchmark on the command line."""

    name: str
    """What follows ``python -m benchmarks``."""
    module: str
    """The module whose ``main(argv=None)`` runs it (imported when the case runs)."""
    summary: str
    """One line: what it prints."""
    needs: str = ""
    """What a run needs beyond this checkout on a CPU (a GPU, newton, a store, a run directory); empty: nothing."""


CASES: tuple[Case, ...] = (
    # body
    Case(name="body-build", module="benchmarks.body_build",
         summary="body build time from scratch, cache-hit load time and model file sizes"),
    Case(name="body-posing", module="benchmarks.body_posing",
         summary="batched posing speed: drape's numpy and torch LBS against smplx's lbs, base and subdivided body"),
    # motions
    Case(name="motions", module="benchmarks.motions",
         summary="procedural motions per label: interpenetration, foot skate, joint limits, jerk, speed, separability"),
    Case(name="motion-sheet", module="benchmarks.motion_sheet",
         summary="contact sheet of every procedural motion label on the default body (docs/motions.png)"),
    Case(name="motion-model", module="benchmarks.motion_model",
         summary="paper 001's motion generator at the paper's size: parameters, sampling speed, training step time"),
    Case(name="motion-train-speed", module="benchmarks.motion_train_speed", needs="a store",
         summary="the motion generator's loader alone, optimiser step alone and both, in segments/s"),
    Case(name="motion-trivial", module="benchmarks.motion_trivial", needs="a store",
         summary="Table 4 for two trivial generators (each label's mean pose held; a copied training segment)"),
    Case(name="motion-split-copy", module="benchmarks.motion_split_copy",
         summary="Table 4's copy and still generators on paper-motion's split and on a held-out style region"),
    Case(name="choose-motion-run", module="benchmarks.choose_motion_run", needs="drape evaluate JSON files",
         summary="per (run, latent) FID, accuracy, diversity, multimodality on the validation split, and the choice"),
    Case(name="sampled-motion-sheet", module="benchmarks.sampled_motion_sheet", needs="drape sample motion output, a store",
         summary="generated motions per label beside real ones (contact sheet) and their mean joint speeds"),
    # garments
    Case(name="garments", module="benchmarks.garments",
         summary="garments over seeds and bodies per type: vertex counts, build time, mesh quality, check failures"),
    Case(name="garment-gallery", module="benchmarks.garment_gallery",
         summary="pictures of every garment type on the default body (docs/garments/)"),
    Case(name="garment-cache", module="benchmarks.garment_cache",
         summary="builds a preset's bodies and garments into drape's cache (for a GPU host without anny or pymeshlab)"),
    Case(name="garment-model", module="benchmarks.garment_model",
         summary="paper 001's garment regressor at the paper's size: parameters and ms per predicted frame"),
    Case(name="garment-table", module="benchmarks.garment_table", needs="drape evaluate JSON files",
         summary="Tables 6/7/9 of the garment regressor from drape evaluate JSON files, the choice per template"),
    Case(name="garment-strain", module="benchmarks.garment_strain", needs="a store",
         summary="largest principal strain of a store's recorded garments per material and sample (median..max)"),
    # paper 000's GNN
    Case(name="gnn", module="benchmarks.gnn",
         summary="paper 000's GNN on a synthetic grid: size, ms per predicted frame (eager, static, graph), training frames/s"),
    Case(name="gnn-loader", module="benchmarks.gnn_loader", needs="a store",
         summary="drape train gnn's loader from a store against the same frames in memory, frames/s"),
    Case(name="gnn-ablations", module="benchmarks.gnn_ablations", needs="drape train gnn run directories",
         summary="paper 000's Figure 10 (validation detail error per epoch per ablation) and its table"),
    # training
    Case(name="train-throughput", module="benchmarks.train_throughput", needs="a store",
         summary="training throughput of the three model kinds on the CPU through Lightning's loop, samples/s and frames/s"),
    # sewing patterns
    Case(name="pattern-survey", module="benchmarks.pattern_survey",
         summary="random pattern designs x thin/regular/fat: how many build, mesh, place and pass the checks; time, vertices, angles"),
    Case(name="pattern-gallery", module="benchmarks.pattern_gallery",
         summary="the gallery of docs/patterns/: flat panels beside the placed 3D panels across the programs and bodies"),
    Case(name="sewing-survey", module="benchmarks.sewing_survey",
         summary="random pattern designs sewn on the bodies at rest: how many sew (gap < 1 mm), settle, pass; causes, time"),
    Case(name="sewing-sequence", module="benchmarks.sewing_sequence",
         summary="pattern garments placed, sewn and settled on the body: the picture docs/patterns/sewing_sequence.png"),
    Case(name="sewing-cusick", module="benchmarks.sewing_cusick",
         summary="the Cusick drape test with the specimen cut as a flat panel (2D rest state), started domed: DC per material"),
    Case(name="pattern-garmentcode", module="benchmarks.pattern_garmentcode",
         summary="GarmentCode specification files read, drawn, meshed and written back: structure and largest difference"),
    # simulator
    Case(name="sim", module="benchmarks.sim",
         summary="the simulator: prepare, run (ms per frame at batch sizes), profile (per kernel), prepare-runs, "
                 "run-scenes (the six 300-frame runs)"),
    Case(name="newton", module="benchmarks.sim_newton", needs="newton for Newton's side (pip install -e '.[newton]')",
         summary="drape's solver and Newton's VBD side by side on one scene: ms per frame, penetration, crossings"),
    Case(name="convergence", module="benchmarks.convergence",
         summary="hanging strip of every material: elongation against the static answer, oscillation, energy balance"),
    Case(name="physics-limits", module="benchmarks.physics_limits",
         summary="energy balance and statics outside the gentle cases: frame rates, release from strain, a square "
                 "rim, edge lengths"),
    Case(name="cusick", module="benchmarks.cusick",
         summary="the Cusick drape test of every material: drape coefficient and nodes against published ranges"),
    Case(name="strain-regions", module="benchmarks.strain_regions", needs="sim run-scenes --out-dir output",
         summary="where the six runs' high strain sits: panels, openings, seams, p99 per saved frame"),
    Case(name="crossing-regions", module="benchmarks.crossing_regions", needs="sim run-scenes --out-dir output",
         summary="where a run's cloth crosses itself: panels of each crossing, and how many the body pinches"),
    Case(name="sweep-traffic", module="benchmarks.sweep_traffic",
         summary="bytes one sweep launch reads and writes per colour, and the bandwidth at a measured launch time"),
    Case(name="sim-positions-digest", module="benchmarks.sim_positions_digest",
         summary="SHA-256 of the solver's final positions on the physics tests' scenes (CPU): a refactoring changes no bit"),
    Case(name="kernel-registers", module="benchmarks.kernel_registers", needs="pyelftools (pip install -e '.[kernels]')",
         summary="registers, stack frame and resident threads per SM of every simulator kernel for sm_90 (no GPU)"),
    # store and export
    Case(name="store-read", module="benchmarks.store_read",
         summary="a store's read throughput per access pattern against the same arrays in memory (or a synthetic store)"),
    Case(name="store-size", module="benchmarks.store_size", needs="a store",
         summary="bytes per stored garment-frame per array, against schema 3; --codecs: position encodings"),
    Case(name="compare-stores", module="benchmarks.compare_stores", needs="two stores",
         summary="two stores array by array: bitwise equal or the largest difference (exit 1 if any differs)"),
    Case(name="kill9", module="benchmarks.kill9",
         summary="kill -9 of drape generate and drape train at random moments: orphans left, resumed store and "
                 "training against uninterrupted ones"),
    Case(name="export", module="benchmarks.export_usd", needs="usd-core (pip install -e '.[usd]')",
         summary="writing a long dense animation to .usd/.usda: seconds, MB, frames/s, validation, read-back"),
    # the README
    Case(name="readme-figures", module="benchmarks.readme_figures",
         summary="every figure README.md quotes, re-measured by its command on this machine (--device cpu|cuda), "
                 "beside README's value; a figure that moved is flagged"),
)
"""Every case, in the order ``--list`` prints them."""


def find(name: str) -> Case:
    """The case called ``name``; ``SystemExit`` (with the names there are) when none is."""
    for case in CASES:
        if case.name == name:
            return case
    raise SystemExit(f"no benchmark case {name!r}; `python -m benchmarks --list` prints them")


def run(case: Case, argv: list[str]) -> int:
    """Import ``case``'s module and run its ``main(argv)``; its exit status."""
    module = importlib.import_module(case.module)
    sys.argv[0] = f"python -m benchmarks {case.name}"  # argparse's usage line names the case, not the module
    status = module.main(argv)
    return int(status or 0)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="python -m benchmarks", description=__doc__.split("\n\n")[0],
        epilog="`python -m benchmarks CASE --help` prints a case's own arguments; benchmarks/README.md lists them.")
    ap.add_argument("--list", action="store_true", help="print every case with what it prints, and stop")
    ap.add_argument("case", nargs="?", help="the case to run")
    ap.add_argument("args", nargs=argparse.REMAINDER, help="the case's arguments")
    args = ap.parse_args(argv)
    if args.list or not args.case:
        width = max(len(c.name) for c in CASES)
        for c in CASES:
            print(f"{c.name:{width}}  {c.summary}" + (f" [needs {c.needs}]" if c.needs else ""))
        return 0
    return run(find(args.case), args.args)
