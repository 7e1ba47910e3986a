"""The garments' templates: every garment instance settled at rest on its body, the shape a store
keeps as ``garments/rest_vertices`` (and from which the indicator, the skinning weights and the fit
attribute are made); its construction, where its scenes start, is ``garments/built_vertices``.

The template is the simulator's settle in the rest pose, run on its own for each instance: the
scene's phases up to the end of the rest settle (:func:`datagen.sim.scene.settled_frame`), with no
lead-in, pose settle or ramp, on a motion of one frame in the rest pose, at the origin. A scene
settles the same garment on the same body at its motion's first translation, and the settle is
sensitive to that translation's float rounding (contacts decided differently): on ``tiny``'s
settings a T-shirt's settle moved by 1 µm or by (0.3, 0, 0.2) m differs from its template by 0.2 mm
per vertex on average (9 mm at most), against the 21 mm by which the settle moves it from its
construction (18.7 mm down). An instance whose settle fails (a gate, a NaN) keeps its construction
and ``garments/settled`` = 0.

A **pattern garment** was sewn on its body at rest and settled there under gravity before
(:func:`datagen.sim.sewing.sew`, its :class:`~datagen.generate.garments.SewingRecord`): when that
settle got static, the sewn garment is its template as it is, not settled again (a static garment
is where a scene's settle leaves it); when it did not (sewing's ``settle_frames`` ran out), it is
settled here like a shell, since a scene's settle still moves it (``tiny-pattern``'s dress by 34 mm
per vertex on average). A design that could not be sewn keeps what sewing left, ``settled`` = 0.
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
    """The template of every garment instance of ``plan`` (module doc): a pattern garment sewn and
    static, its own vertices; a shell, or a sewn garment that did not get static, settled at rest on
    its body here, in batches of the config's ``batch_size`` on ``device``.

    Args:
        plan: the dataset's :class:`~datagen.generate.plan.Plan` (its :meth:`~datagen.generate.plan.Plan.sewing`
            says how each pattern garment was sewn).
        garments: its garment instances (:class:`~datagen.garment.mesh.GarmentMesh`, in order).
        device: warp device (None: warp's default).

    Returns:
        (templates, settled, figures): per instance its template [V, 3] float64 (m, the body's rest
        frame), whether it is the settled drape (uint8 [G]; 0: the construction, the settle
        failed or the design could not be sewn), and figures: ``seconds`` (the settle here),
        ``failed`` (instance -> reason), ``shift_y`` (per instance settled here the mean vertical
        move from the construction to the template, m; else 0) and ``settled_here`` (how many
        instances were settled here).
    """
    from datagen.sim.scene import Scene, settled_frame, simulate

    config = settle_config(plan.run_config)
    motion = rest_motion(plan.config.fps)
    at = settled_frame(config)
    templates = [np.asarray(g.vertices, dtype=np.float64) for g in garments]
    settled = np.zeros(len(garments), np.uint8)
    figures: dict = {"failed": {}, "shift_y": [0.0] * len(garments)}
    here = []  # the instances settled here: shells and sewn garments that did not get static
    for g in range(len(garments)):
        sewing = plan.sewing(g)
        if sewing is None or (sewing.failure is None and not sewing.static):
            here.append(g)
        elif sewing.failure is None:
            settled[g] = 1  # sewn and settled under gravity until static: its own template
        else:
            figures["failed"][g] = str(sewing.failure)
    figures["settled_here"] = len(here)
    unsewn = len(figures["failed"])
    bs = plan.config.simulation.batch_size
    t0 = time.perf_counter()
    for k in range(0, len(here), bs):
        idx = here[k:k + bs]
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
    shifts = np.array(figures["shift_y"])[[g for g in here if settled[g]]]
    log.info("templates: %d of %d garment instances settled at rest in %.1f s (mean vertical move from the "
             "construction %s); %d sewn and static before, their own templates; %d could not be sewn",
             int(settled[here].sum()), len(here), figures["seconds"],
             f"{1000 * shifts.min():+.1f} .. {1000 * shifts.max():+.1f} mm" if len(shifts) else "none",
             len(garments) - len(here) - unsewn, unsewn)
    return templates, settled, figures
