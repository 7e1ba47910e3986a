"""What drape's benchmark cases share: the case base class, timing, table printing, and the
simulator's benchmark scenes (prepared inputs, batches of copies of one scene, the prepared runs).

Library imports stay inside the functions, so that importing this module costs nothing and a case
that needs no simulator does not load warp.
"""

from __future__ import annotations

import argparse
import pickle
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

# --- the case base class ---------------------------------------------------------------------------


class Benchmark:
    """A benchmark case in three steps, run by :meth:`main` (what the runner calls).

    Subclasses set :attr:`description` (the usage text; a module's ``__doc__`` does) and override
    :meth:`add_arguments`, :meth:`setup` (the inputs, not timed: bodies, meshes, stores), :meth:`run`
    (the measurement: what it returns is the result) and :meth:`report` (prints the result). A module
    whose case is a ``Benchmark`` ends with ``main = TheCase().main``.
    """

    description: str = ""

    def add_arguments(self, parser: argparse.ArgumentParser) -> None:
        """Add the case's arguments (none by default)."""

    def setup(self, args: argparse.Namespace) -> Any:
        """Build the inputs of :meth:`run` from the parsed arguments (by default: the arguments)."""
        return args

    def run(self, inputs: Any) -> Any:
        """Measure; the result goes to :meth:`report`."""
        raise NotImplementedError

    def report(self, result: Any) -> int | None:
        """Print the result; an exit status (``None``: 0)."""
        raise NotImplementedError

    def main(self, argv: Sequence[str] | None = None) -> int | None:
        ap = argparse.ArgumentParser(description=self.description,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
        self.add_arguments(ap)
        return self.report(self.run(self.setup(ap.parse_args(argv))))


# --- timing ----------------------------------------------------------------------------------------


def best_of(fn: Callable[[], object], repeats: int, *, warmup: int = 0) -> float:
    """The shortest of ``repeats`` wall-clock times of ``fn()`` [s] (the least disturbed run), after
    ``warmup`` untimed calls."""
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def timed(fn: Callable[[], object]) -> tuple[object, float]:
    """``fn()``'s result and its wall-clock time [s]."""
    t0 = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t0


# --- tables ----------------------------------------------------------------------------------------


def print_table(header: Sequence[str], rows: Sequence[Sequence[object]], formats: Sequence[str] = ()) -> None:
    """Print ``rows`` under ``header``, each column right-aligned to its widest cell.

    ``formats``: one format spec per column (``".1f"``, ``","``, ``""``); missing ones are ``""``.
    """
    formats = list(formats) + [""] * (len(header) - len(formats))
    cells = [[format(v, f) for v, f in zip(row, formats, strict=True)] for row in rows]
    widths = [max([len(h)] + [len(r[k]) for r in cells]) for k, h in enumerate(header)]
    print("  ".join(h.rjust(w) for h, w in zip(header, widths, strict=True)))
    for r in cells:
        print("  ".join(c.rjust(w) for c, w in zip(r, widths, strict=True)), flush=True)


# --- the simulator's benchmark scenes --------------------------------------------------------------


def solver_settings(items: Sequence[str], flag: str = "--set") -> dict:
    """``KEY=VALUE`` items as ``SolverConfig`` keyword arguments, checked by drape's config loader
    (unknown fields, wrong types and limits are refused here, naming ``flag``)."""
    from datagen.config import load_config, parse_assignments
    from datagen.sim.solver import SolverConfig

    kw = parse_assignments(list(items), flag)
    load_config(SolverConfig, kw)
    return kw


def scene_name(d) -> str:
    """``garment/motion`` of ``sim prepare``'s inputs (those prepared before the names were kept: the T-shirt walking)."""
    return f"{d['kind'] if 'kind' in d else 'tshirt'}/{d['motion'] if 'motion' in d else 'walk'}"


@dataclass(frozen=True, kw_only=True)
class Batch:
    """``n`` copies of one scene in one model, ready to step (:func:`build_batch`)."""

    model: Any
    solver: Any
    a: Any
    """The state stepped from (``ClothState``); :func:`play` alternates ``a`` and ``c``."""
    c: Any
    control: Any
    """The body's control (``BodyControl``), at the first body frame."""


def build_batch(*, garment: np.ndarray, faces: np.ndarray, material: str, material_frames: np.ndarray,
                body: np.ndarray, body_faces: np.ndarray, body_face_part: np.ndarray | None, n: int, device: str,
                config) -> Batch:
    """``n`` copies of one garment (``garment`` (V, 3) m, ``faces`` (F, 3)) on one body (``body`` (B, 3)
    m, its first frame) as scenes of one model on ``device``, with drape's solver at ``config``
    (a ``SolverConfig``), the body placed."""
    from datagen.sim.model import ClothModelBuilder
    from datagen.sim.solver import SolverVBD
    from datagen.sim.state import BodyControl, ClothState

    b = ClothModelBuilder()
    for s in range(n):
        b.add_cloth(garment, faces, material_name=str(material), scene=s, material_frames=material_frames)
        b.add_body(body, body_faces, scene=s, face_part=body_face_part)
    m = b.finalize(device)
    solver = SolverVBD(m, config)
    ctrl = BodyControl.from_numpy(m, np.tile(body, (n, 1)))
    solver.reset_body(ctrl)
    return Batch(model=m, solver=solver, a=ClothState.from_model(m), c=ClothState.from_model(m), control=ctrl)


def prepared_batch(d, n: int, device: str, frames: int, config) -> tuple[Batch, list[np.ndarray]]:
    """``n`` copies of ``sim prepare``'s scene ``d`` (an ``np.load``ed .npz) and the body's first
    ``frames + 1`` frames tiled per scene, (n B, 3) each."""
    body = d["body"]
    batch = build_batch(garment=d["garment"], faces=d["faces"], material=str(d["material"]), material_frames=d["frames"],
                        body=body[0], body_faces=d["body_faces"],
                        body_face_part=d["body_face_part"] if "body_face_part" in d else None,
                        n=n, device=device, config=config)
    return batch, [np.tile(f, (n, 1)) for f in body[:frames + 1]]


def play(solver, a, c, control, frames: Sequence[np.ndarray], dt: float = 1 / 30):
    """Step once per body frame of ``frames`` (a -> c, then c -> a, ...); the states, latest first."""
    for f in frames:
        control.set(f)
        solver.step(a, c, control, dt)
        a, c = c, a
    return a, c


def load_runs(path: str | Path) -> dict:
    """``sim prepare-runs``' scenes: ``{"scenes": [Scene, ...], "names": ["garment/motion", ...]}``."""
    with open(path, "rb") as fh:  # our own pickle of our own Scene objects, made by `sim prepare-runs`
        return pickle.load(fh)


def run_output(out_dir: str | Path, name: str) -> Path:
    """Where ``sim run-scenes --out-dir`` saves the run ``name``'s metrics and every 10th recorded frame."""
    return Path(out_dir) / f"{name.replace('/', '_')}.npz"


PRESET_BODIES = ("thin", "regular", "fat")


def preset_bodies(model) -> dict[str, tuple]:
    """The default body's presets at rest: {name: (shaped vertices [V, 3] (m), faces [F, 3],
    BodyMeasurements, betas [S])}, for the pattern cases."""
    from datagen.body.measurements import measure_body
    from datagen.body.shapes import resolve_betas

    bodies = {}
    for name in PRESET_BODIES:
        betas = resolve_betas(model, body=name)[0]
        bodies[name] = (np.asarray(model.shaped(betas))[0], np.asarray(model.faces), measure_body(model, betas), betas)
    return bodies
