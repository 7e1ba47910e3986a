"""The garments of a dataset config: what an entry names, its identity, how it is built, and the
sewing-pattern arrays a store keeps of it.

A config's garment entry is one of:

- ``TYPE:SEED``: a shell garment of a procedural type (``drape garment list``: tshirt, pants, ...);
- ``pattern:PROGRAM:SEED``: a sewing pattern drawn by a pattern program (``drape garment list``'s
  ``patterns``: top, dress, trousers, ...) with design seed ``SEED``, fitted to the body;
- ``spec:PATH`` (or a path ending in ``.json``): a GarmentCode specification file.

Every entry has an identity ``(type name, seed)``, what the store's ``garments/type`` and
``garments/seed`` hold and what splits must not share: a shell ``("tshirt", 0)``, a program
``("pattern:top", 3)``, a file ``("pattern:file", digest)`` where the digest is a 31-bit number from
the file's bytes (the same file under two paths is one design; an edited file is another).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import logging
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from datagen.errors import ConfigError, InputError

log = logging.getLogger(__name__)

PATTERN_PREFIX = "pattern:"
SPEC_PREFIX = "spec:"
FILE_TYPE = "pattern:file"
"""The type name of garments made from a specification file."""
PATTERN_EDGE_LENGTH = 0.02
"""Edge length [m] of a pattern garment when the config gives none (``drape garment make --pattern``'s)."""


@dataclass(frozen=True, kw_only=True)
class GarmentEntry:
    """One garment entry of a config, parsed.

    Attributes:
        kind: ``shell``, ``program`` or ``file``.
        name: the shell type, the pattern program, or the file's stem.
        seed: the style or design seed (a file: the digest of its bytes).
        path: the specification file (``file`` only).
    """

    kind: str
    name: str
    seed: int
    path: Path | None = None

    @property
    def type_name(self) -> str:
        """The store's type name: the shell type, ``pattern:PROGRAM`` or ``pattern:file``."""
        return {"shell": self.name, "program": PATTERN_PREFIX + self.name, "file": FILE_TYPE}[self.kind]

    @property
    def identity(self) -> tuple[str, int]:
        """(type name, seed): the design's identity (splits must not share one)."""
        return self.type_name, self.seed

    @property
    def is_pattern(self) -> bool:
        return self.kind != "shell"


def _seed(text: str, seed: str, example: str) -> int:
    if not seed.lstrip("-").isdigit():
        raise ConfigError(f"garment {text!r} must be written {example}")
    if seed.startswith("-"):
        raise ConfigError(f"garment {text!r}: the seed must be 0 or more")
    value = int(seed)
    if value >= 2**31:
        raise ConfigError(f"garment {text!r}: the seed must be below 2^31 (the store keeps it as int32)")
    return value


def spec_path(text: str) -> Path | None:
    """The file of a ``spec:PATH`` entry (or a bare ``.json`` path); None for other entries."""
    if text.startswith(SPEC_PREFIX):
        return Path(text[len(SPEC_PREFIX):])
    if text.lower().endswith(".json") and ":" not in text.split("/")[0]:
        return Path(text)
    return None


def file_digest(path: Path) -> int:
    """A 31-bit number from the bytes of ``path``: a specification file's seed (its identity)."""
    return int.from_bytes(hashlib.blake2b(path.read_bytes(), digest_size=4).digest(), "little") & 0x7FFFFFFF


def parse_garment_entry(text: str) -> GarmentEntry:
    """Parse a config's garment entry (module doc); a file entry's file is read (its digest) and
    checked to be a GarmentCode specification.

    Raises:
        ConfigError: an unknown type or program (with the known ones), a bad seed, a missing or
            unreadable file.
    """
    if not isinstance(text, str):
        raise ConfigError(f"a garment entry is text (type:seed, pattern:program:seed or spec:path), got {text!r}")
    path = spec_path(text)
    if path is not None:
        if not path.is_file():
            raise ConfigError(f"garment specification file {path} (in {text!r}) does not exist; give the path of a "
                              "GarmentCode JSON file (drape garment make --write-spec writes one)")
        from datagen.garment.pattern.spec import read_spec

        try:
            read_spec(path)
        except (InputError, ValueError, OSError) as exc:
            raise ConfigError(f"garment specification file {path} is not a GarmentCode specification: {exc}") from None
        return GarmentEntry(kind="file", name=path.stem, seed=file_digest(path), path=path)
    if text.startswith(PATTERN_PREFIX):
        from datagen.garment.pattern.programs import PROGRAMS

        program, sep, seed = text[len(PATTERN_PREFIX):].partition(":")
        if not sep:
            raise ConfigError(f"garment {text!r} must be written pattern:PROGRAM:SEED, e.g. 'pattern:top:0'")
        if program not in PROGRAMS:
            raise ConfigError(f"unknown pattern program {program!r} in {text!r}; choose from: {', '.join(PROGRAMS)} "
                              "(drape garment list)")
        return GarmentEntry(kind="program", name=program, seed=_seed(text, seed, f"pattern:{program}:SEED"))
    from datagen.garment.types import GARMENT_TYPES

    name, sep, seed = text.partition(":")
    if not sep:
        raise ConfigError(f"garment {text!r} must be written type:seed (e.g. 'tshirt:0'), pattern:PROGRAM:SEED or "
                          "spec:PATH")
    if name not in GARMENT_TYPES:
        raise ConfigError(f"unknown garment {name!r} in {text!r}; choose from: {', '.join(GARMENT_TYPES)}, or a "
                          "pattern program as pattern:PROGRAM:SEED")
    return GarmentEntry(kind="shell", name=name, seed=_seed(text, seed, f"{name}:SEED"))


def store_type_names() -> list[str]:
    """A store's ``garment_type_names``: the shell types by their frozen codes, then
    ``pattern:PROGRAM`` for every pattern program, then ``pattern:file``."""
    from datagen.garment.pattern.programs import PROGRAMS
    from datagen.garment.registry import garment_type_names

    return [*garment_type_names(), *(PATTERN_PREFIX + p for p in PROGRAMS), FILE_TYPE]


def build_garment(entry: GarmentEntry, body_model, betas, edge_length: float | None, run_config=None,
                  device: str = "cpu"):
    """The :class:`~datagen.garment.mesh.GarmentMesh` of ``entry`` on the body of shape ``betas``
    (:func:`build_instance`), for a caller that needs a garment to simulate.

    Raises:
        InputError: a pattern garment that cannot be sewn on its body, with the reason.
    """
    garment, sewing = build_instance(entry, body_model, betas, edge_length, run_config, device)
    if sewing is not None and sewing.failure is not None:
        raise InputError(f"garment {entry.type_name}:{entry.seed} could not be sewn on its body: {sewing.failure}; "
                         "name another seed or design (`python -m benchmarks sewing-survey` shows which sew)")
    return garment


def build_instance(entry: GarmentEntry, body_model, betas, edge_length: float | None, run_config=None,
                   device: str = "cpu"):
    """(garment, sewing): the :class:`~datagen.garment.mesh.GarmentMesh` of ``entry`` on the body of
    shape ``betas`` (rest pose), and how it was sewn (a :class:`SewingRecord`: whether it could be,
    whether it got static) or None (a shell, or a pattern garment not sewn: no ``run_config``).

    A shell comes from the garment cache; a pattern garment is fitted to the body's measurements (a
    program) or read from its file, meshed at ``edge_length`` (default :data:`PATTERN_EDGE_LENGTH`),
    placed around the body and, given the run's ``run_config`` (a
    :class:`~datagen.sim.scene.RunConfig`), sewn there on warp ``device`` and welded
    (:func:`sewn_garment`). A design that cannot be sewn comes back as what sewing left (welded, not
    settled; the placed panels if it never welded) with its record's failure: a dataset records its
    scenes as failed."""
    if entry.kind == "shell":
        from datagen.garment.cache import cached_garment

        return cached_garment(entry.name, body_model, betas, seed=entry.seed, target_edge_length=edge_length), None
    placed = placed_garment(entry, body_model, betas, edge_length, to_sew=run_config is not None)
    return (placed, None) if run_config is None else sewn_garment(entry, placed, body_model, betas, run_config, device)


def placed_garment(entry: GarmentEntry, body_model, betas, edge_length: float | None, *, to_sew: bool):
    """The pattern garment of ``entry`` (a program's design fitted to the body of shape ``betas``, or
    its file's) meshed at ``edge_length`` (default :data:`PATTERN_EDGE_LENGTH`) and placed around the
    body at rest: flat panels where the pattern puts them when it is ``to_sew``
    (:data:`datagen.sim.sewing.PLACEMENT`), else wrapped around the body."""
    from datagen.garment.pattern.garment import pattern_garment, stand_on_floor
    from datagen.sim.sewing import PLACEMENT

    body_v = np.asarray(body_model.shaped(np.asarray(betas, float).reshape(1, -1)))[0]
    body_f = np.asarray(body_model.faces)
    if entry.kind == "program":
        from datagen.body.measurements import measure_body
        from datagen.garment.pattern.programs import make_pattern

        pattern = make_pattern(entry.name, entry.seed, measure_body(body_model, betas))
    else:
        from datagen.garment.pattern.spec import read_spec, spec_frame

        pattern = read_spec(entry.path)
        if spec_frame(entry.path) == "garmentcode":
            pattern = stand_on_floor(pattern, body_v)
    return pattern_garment(pattern, body_v, body_f, edge_length=edge_length or PATTERN_EDGE_LENGTH,
                           seed=entry.seed if entry.kind == "program" else None, betas=betas,
                           mode=PLACEMENT if to_sew else "wrap")


def sewn_cache_path(entry: GarmentEntry, placed, body_model, betas, run_config) -> Path:
    """Where the garment cache keeps ``placed`` sewn on the body of shape ``betas`` with the run's
    sewing, solver settings and gates: a name made of everything the result depends on (the placed
    panels, the body, the settings; not the device, so a CPU run and a GPU run share what either
    sewed: the two differ by float rounding)."""
    from datagen.body.cache import cache_root

    body_v = np.asarray(body_model.shaped(np.asarray(betas, float).reshape(1, -1)))[0]
    h = hashlib.sha256(json.dumps([str(entry), dataclasses.asdict(run_config.sewing), repr(run_config.solver),
                                   repr(run_config.thresholds)], default=str).encode())
    for a in (placed.vertices, placed.faces, placed.stitch_pairs, body_v):
        h.update(np.ascontiguousarray(a, dtype=np.float64).tobytes())
    return cache_root() / "garments" / f"sewn-{entry.name}-{entry.seed}-{h.hexdigest()[:20]}.npz"


def record_path(path: Path) -> Path:
    """The file beside a sewn garment's cache file that records how it was sewn (:class:`SewingRecord`, JSON)."""
    return path.with_name(path.stem + ".sewing.json")


@dataclass(frozen=True, kw_only=True)
class SewingRecord:
    """How a pattern garment instance was sewn (:func:`datagen.sim.sewing.sew`), kept beside it in the
    garment cache.

    Attributes:
        failure: why it could not be sewn (a :class:`~datagen.sim.metrics.Failure`, code ``seam``), or None.
        sew_frames: frames sewing took to close the seams (-1: they did not close, or not known).
        settle_frames: frames its settle under gravity took to be static (-1: it did not get static
            within ``sewing.settle_frames``, or not known: a garment cached without its record).
        seconds: wall time of the sewing [s] (0 when not known).
        device: the warp device it was sewn on ("" when not known).
    """

    failure: object = None
    sew_frames: int = -1
    settle_frames: int = -1
    seconds: float = 0.0
    device: str = ""

    @property
    def static(self) -> bool:
        """Sewn and settled until static: its drape is its template (not settled again)."""
        return self.failure is None and self.settle_frames >= 0

    def to_json(self) -> str:
        failure = None if self.failure is None else {"code": self.failure.code, "message": self.failure.message}
        return json.dumps({**dataclasses.asdict(self), "failure": failure})

    @classmethod
    def from_json(cls, text: str) -> SewingRecord:
        from datagen.sim.metrics import Failure

        d = json.loads(text)
        return cls(**{**d, "failure": None if d["failure"] is None else Failure(**d["failure"])})


def sewn_garment(entry: GarmentEntry, placed, body_model, betas, run_config, device: str = "cpu"):
    """(garment, record): ``placed`` (a pattern garment around the body at rest) sewn there with the
    run's sewing, solver settings and gates on warp ``device`` and welded
    (:func:`datagen.sim.sewing.sew`), and its :class:`SewingRecord`; for a design that cannot be
    sewn, what sewing left and the record of its failure (code ``seam``, the reason). Both are kept in
    the garment cache (:func:`sewn_cache_path`, the record in :func:`record_path` beside it), so a
    design is sewn once whichever process asks; a garment cached without its record (older code,
    which cached only what sewed) reads as sewn, not known to be static."""
    import os
    import uuid

    from datagen.body.skeleton import face_parts
    from datagen.garment.mesh import load_garment
    from datagen.sim.metrics import Failure
    from datagen.sim.sewing import sew

    path = sewn_cache_path(entry, placed, body_model, betas, run_config)
    record_file = record_path(path)
    if path.is_file():
        try:
            garment = load_garment(path)
            return garment, SewingRecord.from_json(record_file.read_text()) if record_file.is_file() else SewingRecord()
        except Exception as e:  # noqa: BLE001 - a damaged cache file is sewn again
            log.warning("sewn garment cache file %s does not read back (%s); sewing again", path, e)
    body_v = np.asarray(body_model.shaped(np.asarray(betas, float).reshape(1, -1)))[0]
    name = f"{entry.type_name}:{entry.seed}"
    t0 = time.perf_counter()
    try:
        r = sew(placed, body_v, np.asarray(body_model.faces),
                body_face_part=face_parts(body_model.weights, body_model.faces), config=run_config.sewing,
                solver=run_config.solver, thresholds=run_config.thresholds, device=device)
        garment = placed if r.garment is None else r.garment
        record = SewingRecord(failure=r.failure, sew_frames=r.sew_frames, settle_frames=r.settle_frames,
                              seconds=r.seconds, device=str(device))
    except InputError as e:  # the design itself (no stitches, a stitch inside one triangle): it cannot be sewn
        garment = placed
        record = SewingRecord(failure=Failure("seam", str(e)), seconds=time.perf_counter() - t0, device=str(device))
    if record.failure is None:
        log.info("garment %s sewn on %s in %d frames, %s, %.1f s", name, device, record.sew_frames,
                 f"static after {record.settle_frames} frames" if record.static else
                 f"not static after {run_config.sewing.settle_frames} frames of settling", record.seconds)
    else:
        log.warning("garment %s could not be sewn on its body (%s); its scenes are recorded as failed", name,
                    record.failure)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        # the record first: the garment file's presence says the result is complete
        tmp = record_file.with_name(f".{record_file.name}.{uuid.uuid4().hex}.tmp")
        tmp.write_text(record.to_json())
        os.replace(tmp, record_file)
        tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex}.tmp.npz")
        garment.save(tmp)
        os.replace(tmp, path)
    except OSError as e:  # the cache is a convenience
        log.warning("could not cache the sewn garment in %s: %s", path.parent, e)
    return garment, record


def design_record(entry: GarmentEntry, garment) -> dict | None:
    """The design record a store keeps of a pattern garment (``garments/design``): the program (or
    ``file``), seed, source, design parameters (the program's, choices by name included) and the
    GarmentCode specification; None for a shell."""
    if not entry.is_pattern:
        return None
    spec = json.loads(garment.pattern) if garment.pattern else None
    design = (spec or {}).get("design") or dict(garment.metadata.params or {})  # the program's own, words too
    return {"program": entry.name if entry.kind == "program" else "file", "seed": entry.seed,
            "source": "program" if entry.kind == "program" else str(entry.path), "parameters": design,
            "pattern": spec}


def corner_rest_uv(garment) -> np.ndarray:
    """The 2D rest coordinate of every triangle corner [F, 3, 2] (m) of a pattern garment: its
    ``rest_uv`` per corner as given ([F, 3, 2], a welded garment's seams have one per panel) or per
    vertex ([V, 2]) taken at the corners."""
    faces = np.asarray(garment.faces)
    if garment.face_uv is not None and (garment.stitch_pairs is None or not len(garment.stitch_pairs)):
        # a sewn, welded garment: its corners' flat rest state in their panels' grain frame (what it simulates from)
        return np.asarray(garment.face_uv, dtype=np.float64)
    ruv = np.asarray(garment.rest_uv, dtype=np.float64)
    if ruv.shape == (len(faces), 3, 2):
        return ruv
    if ruv.ndim == 2 and ruv.shape == (len(garment.vertices), 2):
        return ruv[faces]
    raise InputError(f"a pattern garment's rest_uv is [V, 2] or [F, 3, 2]; got {ruv.shape} for {len(garment.vertices)} "
                     f"vertices and {len(faces)} faces")


def pattern_arrays(entries: list[GarmentEntry], garments: list) -> dict[str, np.ndarray]:
    """The store's sewing-pattern arrays of the garment instances (``garments/panel``,
    ``face_panel``, ``rest_uv``, ``stitches``, ``design`` and their offsets): a shell garment's are
    -1, NaN and no rows (schemas.dataset)."""
    panel, face_panel, rest_uv, stitches, designs = [], [], [], [], []
    for entry, g in zip(entries, garments, strict=True):
        V, F = len(g.vertices), len(g.faces)
        pattern = g.rest_uv is not None
        if pattern != entry.is_pattern:
            raise InputError(f"garment entry {entry} built a {'pattern' if pattern else 'shell'} garment")
        panel.append(np.asarray(g.vertex_region) if pattern else np.full(V, -1))
        face_panel.append(np.asarray(g.face_region) if pattern else np.full(F, -1))
        rest_uv.append(corner_rest_uv(g) if pattern else np.full((F, 3, 2), np.nan))
        stitches.append(np.zeros((0, 2)) if g.stitch_pairs is None else np.asarray(g.stitch_pairs).reshape(-1, 2))
        record = design_record(entry, g)
        designs.append(np.frombuffer(json.dumps(record, allow_nan=False).encode("utf-8"), np.uint8) if record
                       else np.zeros(0, np.uint8))
    offsets = lambda parts: np.concatenate([[0], np.cumsum([len(p) for p in parts])]).astype(np.int64)  # noqa: E731
    return {"panel": np.concatenate(panel).astype(np.int32), "face_panel": np.concatenate(face_panel).astype(np.int32),
            "rest_uv": np.concatenate(rest_uv).astype(np.float32),
            "stitches": np.concatenate(stitches).astype(np.int32).reshape(-1, 2),
            "design": np.concatenate(designs).astype(np.uint8),
            "stitch_start": offsets(stitches), "design_start": offsets(designs)}
