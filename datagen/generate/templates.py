"""The garments' templates: every garment instance settled at rest on its body, the shape a store
keeps as ``garments/rest_vertices`` (and from which the indicator, the skinning weights and the fit
attribute are made). Each garment is settled once for it:

- a **pattern garment** is sewn on its body at rest and settled there under gravity until static
  (:func:`datagen.sim.sewing.sew`, before the static groups): that sewn, settled garment is both
  where its scenes start (``garments/built_vertices``) and its template; it is not settled again.
  A design that could not be sewn keeps what sewing left, ``garments/settled`` = 0.
- a **shell** is placed by its builder; its template is the simulator's settle in the rest pose, run
  on its own for each instance: the scene's phases up to the end of the rest settle
  (:func:`datagen.sim.scene.settled_frame`), with no lead-in, pose settle or ramp, on a motion of
  one frame in the rest pose, at the origin. Its scenes settle it again from its construction (the
  static groups, templates included, are staged before any scene, so that a resumed run or another
  device's process has them): a scene settles the same garment on the same body at its motion's
  first translation, and the settle is sensitive to that translation's float rounding (contacts
  decided differently): on ``tiny``'s settings a T-shirt's settle moved by 1 µm or by (0.3, 0, 0.2)
  m differs from its template by 0.2 mm per vertex on average (9 mm at most), against the 21 mm by
  which the settle moves it from its construction (18.7 mm down). An instance whose settle fails (a
  gate, a NaN) keeps its construction and ``garments/settled`` = 0.
"""

from __future__ import annotations

import dataclasses
import logging
import time

import numpy as np

log = logging.getLogger(__name__)


def rest_motion(fps: float):
    """One frame in the body's rest pose at the origin (a :class:`~datagen.motion.motion.Motion`)."""
    from datagen.motion.motion import Motion

    return Motion(poses=np.zeros((1, 24, 3)), trans=np.zeros((1, 3)), fps=fps, label=-1, label_name="rest",
                  source={"kind": "rest", "doc": "the garment template's settle"})


def settle_config(run_config):
    """``run_config`` cut to the settle in the rest pose: no lead-in, pose settle or ramp."""
    return dataclasses.replace(run_config, lead_in=0.0, settle_pose=0, ramp=0.0)


def settle_templates(plan, garments: list, device: str | None = None) -> tuple[list[np.ndarray], np.ndarray, dict]:
    """The template of every garment instance of ``plan`` (module doc): a sewn pattern garment's
    own vertices; a shell settled at rest on its body here, in batches of the config's
    ``batch_size`` on ``device``.

    Args:
        plan: the dataset's :class:`~datagen.generate.plan.Plan` (its :meth:`~datagen.generate.plan.Plan.sew_failure`
            says which pattern garments could not be sewn).
        garments: its garment instances (:class:`~datagen.garment.mesh.GarmentMesh`, in order).
        device: warp device (None: warp's default).

    Returns:
        (templates, settled, figures): per instance its template [V, 3] float64 (m, the body's rest
        frame), whether it is the settled drape (uint8 [G]; 0: the construction, the settle
        failed or the design could not be sewn), and figures: ``seconds`` (the shells' settle),
        ``failed`` (instance -> reason), ``shift_y`` (per shell instance the mean vertical move from
        the construction to the template, m; 0 for a pattern garment) and ``settled_here`` (the
        shell instances settled).
    """
    from datagen.sim.scene import Scene, settled_frame, simulate

    config = settle_config(plan.run_config)
    motion = rest_motion(plan.config.fps)
    at = settled_frame(config)
    templates = [np.asarray(g.vertices, dtype=np.float64) for g in garments]
    settled = np.zeros(len(garments), np.uint8)
    figures: dict = {"failed": {}, "shift_y": [0.0] * len(garments)}
    shells = []
    for g in range(len(garments)):
        if not plan.entry(g).is_pattern:
            shells.append(g)
        elif plan.sew_failure(g) is None:
            settled[g] = 1  # sewn and settled under gravity until static: its own template
        else:
            figures["failed"][g] = str(plan.sew_failure(g))
    figures["settled_here"] = len(shells)
    bs = plan.config.simulation.batch_size
    t0 = time.perf_counter()
    for k in range(0, len(shells), bs):
        idx = shells[k:k + bs]
        scenes = [Scene(garment=garments[g], body=plan.body_model,
                        betas=plan.betas[plan.bodies.index(plan.instances[g][1])], motion=motion) for g in idx]
        for g, r in zip(idx, simulate(scenes, config, device=device), strict=True):
            ok = (r.failure is None or r.failure_frame > at) and r.settled is not None and np.isfinite(r.settled).all()
            if ok:
                templates[g] = np.asarray(r.settled, dtype=np.float64)
                settled[g] = 1
                figures["shift_y"][g] = float((templates[g][:, 1] - np.asarray(garments[g].vertices)[:, 1]).mean())
            else:
                figures["failed"][g] = str(r.failure) if r.failure is not None else "not finite"
                log.warning("garment instance %d (%s on %s) did not settle (%s): its template is its construction",
                            g, *plan.instances[g], figures["failed"][g])
    figures["seconds"] = time.perf_counter() - t0
    shifts = np.array(figures["shift_y"])[[g for g in shells if settled[g]]]
    patterns = len(garments) - len(shells)
    log.info("templates: %d of %d shell garment instances settled at rest in %.1f s (mean vertical move from the "
             "construction %s); %d of %d pattern garment instances sewn and settled before (their own templates)",
             int(settled[shells].sum()), len(shells), figures["seconds"],
             f"{1000 * shifts.min():+.1f} .. {1000 * shifts.max():+.1f} mm" if len(shifts) else "none",
             int(settled.sum()) - int(settled[shells].sum()), patterns)
    return templates, settled, figures
