"""Cloth material presets in SI units.

Membrane stiffness is given per unit width (N/m, i.e. Young's modulus times thickness), as cloth
measurements report it. Values are representative of published measurements rather than one
sample:

- Stretch and bending stiffness: the orders of magnitude measured on woven and knit fabrics with
  the Kawabata evaluation system (KES) and by Wang, O'Brien and Ramamoorthi, "Data-driven elastic
  models for cloth" (SIGGRAPH 2011), and Miguel et al., "Data-driven estimation of cloth simulation
  models" (Eurographics 2012): wovens (denim, cotton shirting) are one to two orders of magnitude
  stiffer in stretch than knits (jersey); bending stiffness spans about 1e-6 to 1e-4 N·m.
- Areal density: typical fabric weights (silk 60-80 g/m², shirting cotton 110-150 g/m², jersey
  150-200 g/m², denim 300-450 g/m²).
- Poisson's ratio: about 0.2-0.4 for wovens, higher for knits (Penava et al., "Determination of
  the elastic constants of plain woven fabrics by a tensile test in various directions", Fibres &
  Textiles in Eastern Europe 2014).
- Friction: cloth on skin about 0.3-0.6 (Gerhardt et al., "Friction of textiles against skin").
- Locking: fabrics are soft at small strains (crimp straightening, yarns rotating in shear) and
  stiffen by an order of magnitude or more once the yarns are straight or the weave jams (the
  "biphasic" curves of Wang et al. 2011; shear jamming at about 30-40 degrees). A linear membrane
  with the small-strain stiffness lets a soft knit hang 40-50 % stretched from the shoulders; the
  lock (stiffness x ``lock_ratio`` beyond a principal stretch of ``lock_strain``) is the second,
  stiff branch of that curve.

- Drape (re-fitted 2026-11-25): bending, and silk's shear, are fitted so that every preset's Cusick
  drape coefficient lies inside the published range of its fabric (:data:`DRAPE_COEFFICIENT_RANGES`,
  ``benchmarks/cusick.py``, at the garments' 1.5 cm edges and the production solver). With
  the KES-style values before (cotton 1.2e-5, denim 8e-5, wool 4e-5, polyester 1e-5 N·m) every
  woven draped too stiffly (DC 0.72-0.93); the bending of the discrete-shell hinges on these meshes
  acts stiffer than the continuum's, and the fitted values (cotton 3.5e-6, denim 2e-5, wool 1.5e-5,
  polyester 3e-6 N·m) lie at the low end of KES measurements of those fabrics (0.03-0.2 gf·cm²/cm).
  Silk's DC barely moved with its bending (0.49 at 1.5e-6, 0.48 at 5e-7, 0.44 at 1 cm edges):
  linear triangles lock in shear, so a fold that needs the cloth to shear is held by its 20 N/m
  (at 5 N/m the disc drapes at 0.37, inside silk's range, but the silk dress walking then sheared
  its triangles to 410 % and crossed itself: ``docs/bench/six_runs_refit_silkshear4_h100.txt``).
  Silk keeps its 20 N/m. What lets it fold is the buckling branch (2026-11-26).
- Buckling: every woven preset has ``buckling_ratio`` 0.1. A fabric compressed in its plane buckles at
  once: its bending length sqrt(B/k) is 0.03-0.22 mm for these presets, so its folds start far
  finer than a garment's 1.5 cm triangles, which must shorten instead, nearly freely. With the
  linear law (ratio 1) a triangle resisted shortening as hard as stretching: silk draped at 0.459
  (range 0.2-0.4), and garments strained where they had to fold (the walking silk dress p99 13.7 %,
  the pants 14.0 %). Silk drapes at 0.350 at 0.1 (0.391 with 1.0 cm edges; 0.380 at 0.3).
  At 0.1 `tiny`'s coarse silk dress on the fat body crosses itself (57 crossings at frame 97)
  where at 0.3 it passes; but at 0.3 the six runs' walking dress strains more (p99 10.7 % against
  6.6 %) and comes near the crossing limit (47 against 6), so silk has 0.1. The other wovens stay
  in their ranges at 0.1 with the bending above (cotton 0.504, denim 0.672, polyester 0.477, wool 0.645;
  ``docs/bench/cusick_buckling_cpu.txt``). Jersey keeps the linear law (ratio 1; DC 0.408, and 0.376
  at 0.1): its T-shirts cross themselves on the CPU either way (walk: 58 crossings at frame 73
  with the linear law, 56 at frame 77 at 0.1; dance: 53 at frame 123, 52 at frame 104; limit 50),
  and only the linear law has been run on a GPU, where the walk passes. The knit buckles too; its
  ratio waits for a GPU run of the T-shirts with it.
- Breaking: ``max_strain`` is the stretch gate. Woven apparel fabrics break at 10-45 % elongation
  in strip tests (ISO 13934-1; cotton and silk shirting 10-25 %, denim 15-25 %, polyester and wool
  20-40 %): a triangle of a woven stretched by more than 45 %, the top of that range, is torn
  cloth or a simulation artefact, and the scene is failed (50 % until 2026-11-26; the largest
  strain of a woven that passes the six 300-frame runs and `small` is 30-34 %, so the gate is met
  with margin where the cloth is sound; the garments that the squat tore, 52-84 %, failed it
  before the squat's arms and the body friction in folds were mended). A
  gate at each fabric's own breaking strain (25 % for cotton, silk and denim) would fail those
  runs: their largest single-triangle strain, in a fold or under a contact, is beyond what the
  fabric survives, which says the recorded peaks are still not cloth-like. Knits stretch far more
  before breaking (single jersey 100-300 % along the course): 100 %.

These are approximate presets for simulation, not measurements of particular fabrics; a user with
measured values passes their own :class:`Material`.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from datagen.errors import InputError

__all__ = ["DRAPE_COEFFICIENT_RANGES", "MATERIALS", "Material", "drape_range", "material"]


_POSITIVE = {"density": "[kg/m²]", "stretch_warp": "[N/m]", "stretch_weft": "[N/m]", "shear": "[N/m]",
             "thickness": "[m]"}
"""Material values that must be > 0, with their units."""
_NON_NEGATIVE = {"bending": "[N·m]", "friction": "[-]", "damping": "[s]"}
"""Material values that must be >= 0, with their units."""


@dataclass(frozen=True, kw_only=True)
class Material:
    """A cloth material (SI units).

    Attributes:
        name: preset name.
        density: areal density [kg/m²].
        stretch_warp: membrane stretch stiffness along the warp (v) direction [N/m].
        stretch_weft: membrane stretch stiffness along the weft (u) direction [N/m].
        shear: in-plane shear stiffness [N/m].
        poisson: Poisson's ratio [-].
        bending: bending stiffness [N·m].
        friction: Coulomb friction coefficient against skin [-].
        thickness: cloth thickness used as collision distance [m].
        damping: stiffness-proportional damping [s].
        lock_strain: principal stretch [-] beyond which the fabric locks (its yarns straightened,
            its weave jammed in shear) and the membrane stiffens.
        lock_ratio: the membrane stiffness added beyond ``lock_strain``, as a multiple of the
            larger stretch stiffness [-].
        max_strain: the largest principal strain [-] a triangle of this fabric may reach before
            the simulation is failed (``stretch``): beyond the fabric's breaking elongation the
            cloth would have torn, so such a frame is a simulation artefact, not data.
        buckling_ratio: the membrane's stretch stiffness under compression, as a fraction of its
            stiffness in tension [-], per material direction (1: the linear law, as stiff in
            compression as in tension). Cloth compressed in its plane buckles at once, into folds
            finer than a garment's triangles can show; those triangles must shorten instead, and a
            membrane as stiff in compression as in tension holds a drape that the real fabric
            makes (Choi and Ko 2002, "Stable but responsive cloth": the post-buckling response;
            Marvelous Designer's "buckling ratio" is the same setting).
    """

    name: str
    density: float
    stretch_warp: float
    stretch_weft: float
    shear: float
    poisson: float
    bending: float
    friction: float
    thickness: float
    damping: float = 0.002
    lock_strain: float = 0.3
    lock_ratio: float = 20.0
    max_strain: float = 1.0
    buckling_ratio: float = 1.0

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name:
            raise InputError(f"a material needs a name (a non-empty string), got {self.name!r}")
        for key in ("density", "stretch_warp", "stretch_weft", "shear", "poisson", "bending", "friction", "thickness",
                    "damping", "lock_strain", "lock_ratio", "max_strain", "buckling_ratio"):
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise InputError(f"material {self.name!r}: {key} must be a finite number, got {value!r}")
        for key, unit in _POSITIVE.items():
            if not getattr(self, key) > 0:
                raise InputError(f"material {self.name!r}: {key} must be > 0 {unit}, got {getattr(self, key)} "
                                 "(a stiffness, density or thickness of zero or less is no fabric)")
        for key, unit in _NON_NEGATIVE.items():
            if getattr(self, key) < 0:
                raise InputError(f"material {self.name!r}: {key} must be >= 0 {unit}, got {getattr(self, key)}")
        if not 0 <= self.poisson < 1:
            raise InputError(f"material {self.name!r}: poisson must be in [0, 1) (the membrane's coupling of its two "
                             f"stretches stays positive definite below 1), got {self.poisson}")
        if not self.max_strain > 0:
            raise InputError(f"material {self.name!r}: max_strain must be > 0, got {self.max_strain}")
        if not (self.lock_strain > 0 and self.lock_ratio >= 0):
            raise InputError(f"material {self.name!r}: lock_strain must be > 0 and lock_ratio >= 0, got "
                             f"{self.lock_strain} and {self.lock_ratio}")

        if not 0 < self.buckling_ratio <= 1:
            raise InputError(f"material {self.name!r}: buckling_ratio must be in (0, 1] (compression as a fraction "
                             f"of the tension stiffness), got {self.buckling_ratio}")

    def as_dict(self) -> dict:
        return asdict(self)

    @property
    def poisson_coupling(self) -> float:
        """k_uv = ν sqrt(k_u k_v) [N/m], the membrane law's coupling of its two stretches."""
        return self.poisson * (self.stretch_weft * self.stretch_warp) ** 0.5

    def warp_uniaxial_stiffness(self) -> float:
        """The stiffness [N/m] of a strip pulled along the warp with its sides free: k_v - r k_uv²/k_u.
        The weft contracts under the Poisson coupling (k_uv/k_u of the warp's Green strain), which
        is compression, so its stiffness and the coupling are on the buckling branch (x r each)."""
        return self.stretch_warp - self.buckling_ratio * self.poisson_coupling ** 2 / self.stretch_weft


MATERIALS: dict[str, Material] = {
    "cotton": Material(name="cotton", density=0.13, stretch_warp=1800.0, stretch_weft=1200.0, shear=60.0,
                       poisson=0.3, bending=3.5e-6, friction=0.45, thickness=0.0015, max_strain=0.45, buckling_ratio=0.1),
    "denim": Material(name="denim", density=0.40, stretch_warp=6000.0, stretch_weft=3500.0, shear=200.0,
                      poisson=0.25, bending=2.0e-5, friction=0.5, thickness=0.0025, max_strain=0.45, buckling_ratio=0.1),
    "jersey": Material(name="jersey", density=0.18, stretch_warp=120.0, stretch_weft=60.0, shear=15.0,
                       poisson=0.45, bending=3.0e-6, friction=0.4, thickness=0.0015, max_strain=1.0),
    "silk": Material(name="silk", density=0.07, stretch_warp=900.0, stretch_weft=700.0, shear=20.0,
                     poisson=0.3, bending=5.0e-7, friction=0.3, thickness=0.001, max_strain=0.45, buckling_ratio=0.1),
    "polyester": Material(name="polyester", density=0.15, stretch_warp=2500.0, stretch_weft=2000.0, shear=80.0,
                          poisson=0.3, bending=3.0e-6, friction=0.35, thickness=0.0015, max_strain=0.45, buckling_ratio=0.1),
    "wool": Material(name="wool", density=0.30, stretch_warp=1500.0, stretch_weft=1000.0, shear=70.0,
                     poisson=0.3, bending=1.5e-5, friction=0.5, thickness=0.003, max_strain=0.45, buckling_ratio=0.1),
}
"""The presets, by name."""


def material(name: str | Material) -> Material:
    """A preset by name (or a :class:`Material` passed through); unknown names list the presets."""
    if isinstance(name, Material):
        return name
    try:
        return MATERIALS[name]
    except KeyError:
        raise InputError(f"unknown material {name!r}; presets: {', '.join(MATERIALS)}") from None


DRAPE_COEFFICIENT_RANGES: dict[str, tuple[float, float]] = {
    "silk": (0.20, 0.40),
    "cotton": (0.40, 0.60),
    "jersey": (0.30, 0.50),
    "denim": (0.60, 0.85),
    "wool": (0.50, 0.75),
    "polyester": (0.35, 0.65),
}
"""Cusick drape coefficients of the real fabrics each preset stands for (30 cm specimen on an
18 cm support, BS 5058 / ISO 9073-9), approximate ranges over published measurements: Cusick,
"The measurement of fabric drape", J. Textile Inst. 59 (1968) 253-260; Hu and Chan, "Effect of
fabric mechanical properties on drape", Textile Res. J. 68 (1998) 57-64 (woven apparel fabrics);
Jeong and Phillips, "A study of fabric-drape behaviour with image analysis, part II", J. Textile
Inst. 89 (1998) 70-79. Light silks and chiffons 0.2-0.4, cotton shirting 0.4-0.6, jersey knits
0.3-0.5, denim 0.6-0.85, wool suiting 0.5-0.75, polyester shirting and blouse wovens 0.35-0.65
(the widest: from soft georgettes to crisp taffetas). ``benchmarks/cusick.py`` drapes every
preset and checks it against its range."""


def drape_range(name: str) -> tuple[float, float]:
    """The Cusick drape-coefficient range of preset ``name`` (:data:`DRAPE_COEFFICIENT_RANGES`)."""
    try:
        return DRAPE_COEFFICIENT_RANGES[name]
    except KeyError:
        raise InputError(f"no drape-coefficient range for {name!r}; presets: {', '.join(DRAPE_COEFFICIENT_RANGES)}") from None
