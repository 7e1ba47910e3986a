"""Schema of drape's dataset store (version 6): every group and array of the packed zarr v3 store
with its symbolic shape, dtype, unit and meaning, the table whose rows its first axis runs over,
and every required root attribute. ``datagen.store`` writes, reads and validates against this
module and nothing else; ``docs/store.md`` explains it in prose.

A *sample* is one simulated scene: one garment instance on one body doing one motion, with ``T``
recorded frames of ``V`` garment vertices (``V`` differs per garment instance, ``T`` per sample) over
``T_sim >= T`` simulated frames (settle and lead-in included). A failed scene is a sample too: ``T = 0``
(no frame data), a nonzero ``failure`` code, and its per-simulation-frame metrics; its motion's poses
stay in ``motions/pose`` and ``motions/trans``, written for every motion of the config.

Packed, ragged per-sample data are concatenated over (sample, frame, vertex) into flat *tables*
indexed by offset arrays (``index/frame_start``, ``index/vertex_row_start``,
``index/sim_frame_start``): sample ``i`` has frames ``frame_start[i]:frame_start[i + 1]`` of the
``frame`` table, and its frame ``t`` (global frame row ``f = frame_start[i] + t``) has vertex rows
``vertex_row_start[f]:vertex_row_start[f + 1]`` of the ``vertex_frame`` table.

Symbols in shapes (see :data:`DIMENSIONS`) are bound by the data; integers are fixed. No array holds
text: codes are integers and their names are root attributes (:data:`NAME_LISTS`), so every array
reads in any zarr v3 reader (tensorstore's ``zarr3`` driver included); the one JSON record a garment
has (its design, ``garments/design``) is UTF-8 bytes in a uint8 array, so it reads the same way.
"""

from __future__ import annotations

from dataclasses import dataclass

DATASET_SCHEMA_VERSION = 6
"""6: garments keep their sewing pattern (per-corner 2D rest coordinates, panels, stitches, the design
as JSON) and ``garments/rest_vertices`` is the settled drape at rest (the builder's construction is
``garments/built_vertices``). 5: every motion's recorded poses and translations (``motions/pose``,
``motions/trans``), whether its scenes passed or failed, so that a motion model learns every motion
of the config. 4: positions quantised (``detail``, ``coarse``), derived arrays no longer stored
(they come from :mod:`datagen.features`), the subdivided body's topology stored, the fit attribute
optional.
3: the code version recorded. 2: the slip metric."""

REFUSED_VERSIONS: dict[int, str] = {
    5: "version 5 kept the builder's construction as the garment's rest shape (not the settled drape the scenes "
       "start their motion from) and no sewing pattern (2D rest coordinates, panels, stitches, design)",
    4: "version 4 kept the poses of passed samples only (no motions/pose, motions/trans): a motion whose scenes "
       "all failed was lost to the motion generator",
    3: "version 3 stored the derived arrays (body vertices, anchors, normals, skinning features, joint distances) "
       "that version 4 derives on read, and positions as float32",
    2: "version 2 had no code version",
    1: "version 1 had no slip metric",
}
"""Why each older schema version is refused (a store is made again; it is a pure function of its config)."""

POSITION_QUANTUM = 5.0e-5
"""Step (m) of the stored garment positions: ``detail`` and ``coarse`` are int32 multiples of it,
relative to the frame's root joint (``frames/joints[:, 0]``). Rounding to the nearest step bounds
the error at half a step, 0.025 mm, plus float32 rounding of the decoded sum (< 1e-7 m within 2 m
of the root); int32 spans +-107 km, so no position is out of range."""

STORE_FORMAT = "drape-dataset"
"""Value of the root attribute ``format`` that marks a zarr group as a drape dataset store."""

JOINT_COUNT = 24
"""SMPL's joints (order and parents as ``datagen.body.skeleton``)."""

SPLIT_NAMES: tuple[str, ...] = ("train", "val", "test")
"""Split codes: ``samples/split`` = index into this tuple."""

FAILURE_NAMES: tuple[str, ...] = ("ok", "nan", "penetration", "self-intersection", "stretch", "slip", "seam")
"""Default failure codes (``samples/failure`` = index; 0 = ok): the reasons ``datagen.sim.metrics``
gives, by the word before their colon. A store may be created with a longer list."""

SEGMENT_LENGTH = 60
"""Default frames per segment (paper 001 cuts sequences into T = 60 segments)."""


@dataclass(frozen=True, kw_only=True)
class Chunking:
    """How a table's arrays are chunked and sharded along their first axis (other axes whole).

    Attributes:
        chunk_bytes: target uncompressed bytes of one chunk (the unit of reading and compression);
            a chunk holds the largest power of two of rows that fits (at least one row).
        shard_bytes: target uncompressed bytes of one shard (the unit of a file on disk and of
            writing); a shard holds the largest power of two of chunks that fits (at least one).
    """

    chunk_bytes: int
    shard_bytes: int


@dataclass(frozen=True, kw_only=True)
class Table:
    """A set of arrays whose first axes run over the same rows.

    Attributes:
        rows: the dimension symbol of the row count.
        offsets: path of the offset array into these rows (``None``: rows are indexed directly).
        offsets_per: the table one offset entry belongs to (offset array length = its rows + 1).
        chunking: chunk and shard sizes of the table's arrays.
        doc: what one row is.
    """

    rows: str
    offsets: str | None = None
    offsets_per: str | None = None
    chunking: Chunking
    doc: str


@dataclass(frozen=True, kw_only=True)
class ArraySpec:
    """One array of the packed store.

    Attributes:
        path: group/name inside the store; ``name`` (the part after the slash) is the key handed
            to the writer and returned by the reader.
        shape: packed shape on disk, symbols from :data:`DIMENSIONS` or fixed integers.
        sample_shape: shape of one sample's array as handed to ``StoreWriter.stage_sample``
            (``()``: a per-sample scalar); ``None`` for arrays not written per sample.
        dtype: numpy dtype name on disk.
        unit: the ``unit`` attribute of the array ("1": dimensionless; "index": a row index;
            "code": an integer whose names are in ``codes``; "row": an offset into rows).
        doc: meaning (becomes the ``doc`` attribute of the array).
        table: the :data:`TABLES` entry whose rows the first axis runs over.
        written_by: ``stage_sample``, ``stage_static`` (group = first part of ``path``) or ``pack``.
        codes: root attribute listing the names of the values (valid values ``minimum`` to
            ``len(names) - 1``).
        index_of: dimension symbol whose size bounds the values (valid ``minimum`` to size - 1).
        minimum: smallest valid value of a code or index array (-1: "none"/"unlabelled").
        finite: float arrays: ``"all"`` (every value finite), ``"ok_samples"`` (finite in samples
            with ``failure == 0``; a failed sample may hold inf/nan from the step that failed) or
            ``"fitted"`` (finite when the root attribute ``fit_attribute`` is true, NaN otherwise) or
            ``"pattern"`` (finite on the rows of pattern garments, ``face_panel >= 0``; NaN on shells').
        quantum: positions stored as integers: the value in ``unit`` is ``stored * quantum +`` the
            frame's root joint (``frames/joints[:, 0]``); the writer takes and the reader returns
            float32 metres.
        compression: the chunk compressor, as :data:`COMPRESSION` (``None``: :data:`COMPRESSION`).
    """

    path: str
    shape: tuple[str | int, ...]
    sample_shape: tuple[str | int, ...] | None = None
    dtype: str
    unit: str
    doc: str
    table: str
    written_by: str
    codes: str | None = None
    index_of: str | None = None
    minimum: int | None = None
    finite: str = "all"
    quantum: float | None = None
    compression: dict | None = None

    @property
    def group(self) -> str:
        return self.path.split("/")[0]

    @property
    def name(self) -> str:
        return self.path.split("/")[1]


@dataclass(frozen=True, kw_only=True)
class AttributeSpec:
    """A required root attribute: JSON ``type`` (``int``, ``str``, ``bool``, ``dict``, ``list[str]``)
    and meaning; ``staged_with`` names the static group whose ``stage_static`` call gives a name list."""

    type: str
    doc: str
    staged_with: str | None = None


DIMENSIONS: dict[str, str] = {
    "n_samples": "samples, failed ones included (root attribute sample_count)",
    "n_frames": "recorded frames over all samples (sum of T)",
    "n_vertex_rows": "garment vertex-frames over all samples (sum over samples of T * V)",
    "n_sim_frames": "simulated frames over all samples (sum of T_sim)",
    "n_segments": "segments of segment_length frames (root attribute)",
    "T": "recorded frames of one sample (0 for a failed sample)",
    "V": "vertices of one garment instance",
    "T_sim": "simulated frames of one sample, settle and lead-in included (T_sim >= T)",
    "J": f"joints ({JOINT_COUNT}, SMPL order)",
    "B": "body vertices (the stored body model's vertex count)",
    "S": "shape components (betas)",
    "Fb": "body triangles",
    "n_bodies": "bodies (shape vectors)",
    "M": "motions",
    "T_m": "recorded frames of every motion (the config's frames)",
    "G": "garment instances",
    "n_garment_vertices": "garment-instance vertices over all instances (sum of V)",
    "n_garment_faces": "garment-instance triangles over all instances (sum of F)",
    "n_stitches": "stitched vertex pairs over all garment instances (0 for shell garments)",
    "n_design_bytes": "bytes of the garment instances' design records (UTF-8 JSON; 0 for shell garments)",
    "D": "features of the fit-attribute factor-analysis model (0 when the store has no fit attribute)",
    "E": "edges of the body mesh: midpoint vertices of the subdivided body (vertex B + e on edge e)",
    "Fs": "triangles of the subdivided body (4 Fb)",
}
"""Dimension symbols used in shapes, with their meaning."""

FIXED_DIMENSIONS: dict[str, int] = {"J": JOINT_COUNT}

COMPRESSION: dict[str, str | int] = {"codec": "blosc", "cname": "lz4", "clevel": 5, "shuffle": "bitshuffle"}
"""Compressor of every chunk (inside the sharding codec): blosc's lz4 over bit-shuffled values. On
float32 cloth data it decodes ~1.4x faster than blosc-zstd and ~1.6x faster than plain zstd at an
equal or better ratio (benchmarks in docs/store.md); reads, not bytes, limit training."""

POSITION_COMPRESSION: dict[str, str | int] = {"codec": "blosc", "cname": "zstd", "clevel": 5, "shuffle": "bitshuffle"}
"""Compressor of the quantised positions: int32 steps of 0.05 mm from the root joint are small
numbers whose high bits are all equal, which bit-shuffle + zstd packs to ~5.5 B per vertex (lz4:
~6.5 B; float32 with lz4: ~10 B; measured on tiny's garments, docs/store.md)."""

_ROWS = Chunking(chunk_bytes=256 * 1024, shard_bytes=64 * 1024 * 1024)
_SMALL = Chunking(chunk_bytes=1024 * 1024, shard_bytes=64 * 1024 * 1024)

TABLES: dict[str, Table] = {
    "sample": Table(rows="n_samples", chunking=_SMALL, doc="one sample"),
    "frame": Table(rows="n_frames", offsets="index/frame_start", offsets_per="sample", chunking=_ROWS,
                   doc="one recorded frame of one sample, samples in order, frames in order"),
    "vertex_frame": Table(rows="n_vertex_rows", offsets="index/vertex_row_start", offsets_per="frame", chunking=_ROWS,
                          doc="one garment vertex in one recorded frame, ordered by (sample, frame, vertex)"),
    "sim_frame": Table(rows="n_sim_frames", offsets="index/sim_frame_start", offsets_per="sample", chunking=_ROWS,
                       doc="one simulated frame of one sample (settle and lead-in included)"),
    "segment": Table(rows="n_segments", chunking=_SMALL, doc="one segment of segment_length recorded frames"),
    "offset": Table(rows="(varies)", chunking=_SMALL, doc="offset arrays: one entry per row of a table, plus one"),
    "static": Table(rows="(varies)", chunking=_SMALL, doc="a row of a static table (body model, bodies, motions, fit)"),
    "garment": Table(rows="G", chunking=_SMALL, doc="one garment instance"),
    "garment_vertex": Table(rows="n_garment_vertices", offsets="garments/vertex_start", offsets_per="garment",
                            chunking=_ROWS, doc="one rest vertex of one garment instance, instances in order"),
    "garment_face": Table(rows="n_garment_faces", offsets="garments/face_start", offsets_per="garment",
                          chunking=_ROWS, doc="one triangle of one garment instance, instances in order"),
    "garment_stitch": Table(rows="n_stitches", offsets="garments/stitch_start", offsets_per="garment",
                            chunking=_SMALL,
                            doc="one stitched vertex pair of one garment instance, instances in order"),
    "garment_design": Table(rows="n_design_bytes", offsets="garments/design_start", offsets_per="garment",
                            chunking=_SMALL,
                            doc="one byte of one garment instance's design record, instances in order"),
}
"""Row tables and their chunking (see ``docs/store.md`` for why these sizes)."""


def _vertex(name: str, k: int | str, unit: str, doc: str) -> ArraySpec:
    return ArraySpec(path=f"vertex_frames/{name}", shape=("n_vertex_rows", k), sample_shape=("T", "V", k),
                     dtype="int32", unit=unit, doc=doc, table="vertex_frame", written_by="stage_sample",
                     quantum=POSITION_QUANTUM, compression=POSITION_COMPRESSION)


def _frame(name: str, tail: tuple, dtype: str, unit: str, doc: str, **kw) -> ArraySpec:
    return ArraySpec(path=f"frames/{name}", shape=("n_frames", *tail), sample_shape=("T", *tail), dtype=dtype,
                     unit=unit, doc=doc, table="frame", written_by="stage_sample", **kw)


def _metric(name: str, dtype: str, unit: str, doc: str) -> ArraySpec:
    return ArraySpec(path=f"sim_frames/{name}", shape=("n_sim_frames",), sample_shape=("T_sim",), dtype=dtype,
                     unit=unit, doc=doc, table="sim_frame", written_by="stage_sample",
                     finite="ok_samples" if dtype.startswith("float") else "all")


def _scalar(name: str, dtype: str, unit: str, doc: str, **kw) -> ArraySpec:
    return ArraySpec(path=f"samples/{name}", shape=("n_samples",), sample_shape=(), dtype=dtype, unit=unit, doc=doc,
                     table="sample", written_by="stage_sample", **kw)


def _static(path: str, shape: tuple, dtype: str, unit: str, doc: str, table: str = "static", **kw) -> ArraySpec:
    return ArraySpec(path=path, shape=shape, dtype=dtype, unit=unit, doc=doc, table=table, written_by="stage_static",
                     **kw)


def _offset(path: str, shape: tuple, doc: str, dtype: str = "int64", unit: str = "row", **kw) -> ArraySpec:
    return ArraySpec(path=path, shape=shape, dtype=dtype, unit=unit, doc=doc, table="offset", written_by="pack", **kw)


_ARRAY_LIST: tuple[ArraySpec, ...] = (
    # --- per vertex and recorded frame: [T, V, k] per sample, packed [n_vertex_rows, k]
    _vertex("detail", 3, "m", "simulated garment vertex positions (stored: int32 steps of quantum from the frame's "
            "root joint)"),
    _vertex("coarse", 3, "m", "smoothed (coarse) garment vertex positions, paper 000 eq. 9 (stored as detail)"),
    # --- per recorded frame: [T, ...] per sample, packed [n_frames, ...]
    _frame("pose", ("J", 3), "float32", "rad", "joint rotations, axis-angle, root first"),
    _frame("trans", (3,), "float32", "m", "root translation"),
    _frame("joints", ("J", 3), "float32", "m", "posed joint positions"),
    _frame("label", (), "int32", "code", "motion label of the frame", codes="label_names", minimum=-1),
    # --- per simulated frame: [T_sim] per sample, packed [n_sim_frames]
    _metric("metric_stretch_max", "float32", "1", "largest principal stretch minus one over the garment's triangles"),
    _metric("metric_stretch_mean", "float32", "1", "area-weighted mean principal stretch minus one"),
    _metric("metric_penetration_count", "int32", "count", "garment vertices inside the body"),
    _metric("metric_penetration_depth", "float32", "m", "depth of the deepest garment vertex inside the body"),
    _metric("metric_self_intersections", "int32", "count", "cloth edges crossing a cloth triangle"),
    _metric("metric_kinetic_energy", "float32", "J", "kinetic energy of the garment"),
    _metric("metric_nan", "uint8", "bool", "1 where a position or velocity was not finite"),
    _metric("metric_slip", "float32", "m", "mean distance the garment's top band moved away from the body points "
            "that carry it"),
    # --- per sample: scalars, packed [n_samples]
    _scalar("garment", "int32", "index", "garment instance (row of the garments/ tables)", index_of="G"),
    _scalar("body", "int32", "index", "body (row of bodies/betas)", index_of="n_bodies"),
    _scalar("motion", "int32", "index", "motion (row of the motions/ tables)", index_of="M"),
    _scalar("split", "int32", "code", "split: 0 train, 1 val, 2 test", codes="split_names"),
    _scalar("failure", "int32", "code", "failure reason, 0 = ok", codes="failure_names"),
    _scalar("failure_frame", "int32", "index", "simulated frame where the sample first failed, -1 if none",
            minimum=-1),
    _scalar("recorded_from", "int32", "index", "first recorded frame within the simulated frames", minimum=0),
    _scalar("seconds", "float32", "s", "simulation wall time spent on the sample"),
    # --- offsets and segments, computed by pack()
    _offset("index/frame_start", ("n_samples+1",), "sample i's frames are frame rows frame_start[i]:frame_start[i+1]"),
    _offset("index/vertex_row_start", ("n_frames+1",),
            "frame row f's vertices are vertex rows vertex_row_start[f]:vertex_row_start[f+1]"),
    _offset("index/sim_frame_start", ("n_samples+1",),
            "sample i's simulated frames are rows sim_frame_start[i]:sim_frame_start[i+1]"),
    _offset("index/segments", ("n_segments", 2),
            "(sample, first recorded frame) of each non-overlapping segment of segment_length frames, over "
            "every non-failed sample with T >= segment_length", unit="index"),
    # --- the body model (SMPL format, no pose blend shapes)
    _static("body/v_template", ("B", 3), "float32", "m", "rest-pose (T-pose) template vertices"),
    _static("body/shapedirs", ("B", 3, "S"), "float32", "m per unit β", "shape blend-shape directions"),
    _static("body/J_regressor", ("J", "B"), "float32", "1", "joint regressor, rows sum to 1"),
    _static("body/weights", ("B", "J"), "float32", "1", "skinning weights, rows sum to 1"),
    _static("body/parents", ("J",), "int32", "index", "parent joint of each joint, -1 for the root", index_of="J",
            minimum=-1),
    _static("body/faces", ("Fb", 3), "int32", "index", "body triangles", index_of="B"),
    _static("body/subdivision_edges", ("E", 2), "int32", "index",
            "the subdivided body (paper 000 §5.1): vertex B + e is the midpoint of edge e's two vertices, in "
            "every quantity linear in the vertices (template, shape directions, skinning weights)", index_of="B"),
    _static("body/subdivided_faces", ("Fs", 3), "int32", "index",
            "triangles of the subdivided body, indices into its B + E vertices"),
    # --- bodies, motions
    _static("bodies/betas", ("n_bodies", "S"), "float32", "1", "shape coefficients of each body"),
    _static("motions/label", ("M",), "int32", "code", "label of each motion", codes="label_names", minimum=-1),
    _static("motions/seed", ("M",), "int32", "1", "seed the motion was generated with"),
    _static("motions/frame_count", ("M",), "int32", "count", "frames of the motion", minimum=0),
    _static("motions/pose", ("M", "T_m", "J", 3), "float32", "rad",
            "joint rotations (axis-angle, root first) of each motion's recorded frames (a sample's frames/pose are its first T), "
            "written for every motion whether its samples passed or failed"),
    _static("motions/trans", ("M", "T_m", 3), "float32", "m",
            "root translation of each motion's recorded frames (a sample's frames/trans are its first T)"),
    # --- garment instances: per instance [G], per vertex [n_garment_vertices], per face [n_garment_faces]
    _static("garments/vertex_start", ("G+1",), "int64", "row",
            "instance g's vertices are rows vertex_start[g]:vertex_start[g+1]", table="offset"),
    _static("garments/face_start", ("G+1",), "int64", "row",
            "instance g's faces are rows face_start[g]:face_start[g+1]", table="offset"),
    _static("garments/stitch_start", ("G+1",), "int64", "row",
            "instance g's stitches are rows stitch_start[g]:stitch_start[g+1] (none for a shell garment)",
            table="offset"),
    _static("garments/design_start", ("G+1",), "int64", "row",
            "instance g's design record is bytes design_start[g]:design_start[g+1] of garments/design (none for a "
            "shell garment)", table="offset"),
    _static("garments/rest_vertices", ("n_garment_vertices", 3), "float32", "m",
            "the garment's template: at rest on its body in the rest pose, the simulator's settled drape where "
            "garments/settled is 1 (the builder's construction where it is 0)", table="garment_vertex"),
    _static("garments/built_vertices", ("n_garment_vertices", 3), "float32", "m",
            "the builder's construction on the body's rest pose (a pattern garment: sewn), where every scene's "
            "simulation starts", table="garment_vertex"),
    _static("garments/faces", ("n_garment_faces", 3), "int32", "index",
            "triangles, vertex indices local to the instance (0 .. V-1)", table="garment_face"),
    _static("garments/uv", ("n_garment_vertices", 2), "float32", "m", "material coordinates (weft, warp)",
            table="garment_vertex"),
    _static("garments/region", ("n_garment_vertices",), "int32", "code", "panel of each vertex", codes="region_names",
            table="garment_vertex"),
    _static("garments/seam", ("n_garment_vertices",), "uint8", "bool", "1 on a seam between two panels",
            table="garment_vertex"),
    _static("garments/indicator", ("n_garment_vertices",), "int32", "index",
            "vertex of the subdivided body each garment vertex is attached to (0 .. B + E - 1)", minimum=0,
            table="garment_vertex"),
    _static("garments/skin_weights", ("n_garment_vertices", "J"), "float32", "1", "skinning weights of the vertex",
            table="garment_vertex"),
    _static("garments/type", ("G",), "int32", "code", "garment type: a shell type, or pattern:PROGRAM (a pattern "
            "program) or pattern:file (a specification file)", codes="garment_type_names", table="garment"),
    _static("garments/seed", ("G",), "int32", "1", "style seed of the instance (the design seed of a pattern program; "
            "of a specification file, a digest of its bytes, so (type, seed) is the design's identity)",
            table="garment"),
    _static("garments/body", ("G",), "int32", "index", "body the instance was made for", index_of="n_bodies",
            table="garment"),
    _static("garments/material", ("G",), "int32", "code", "material", codes="material_names", table="garment"),
    _static("garments/alpha", ("G", 3), "float32", "1", "fit attribute (factor scores under the fit/ model); NaN "
            "when the store has no fit attribute (root attribute fit_attribute false)", table="garment",
            finite="fitted"),
    _static("garments/rest_area", ("G",), "float32", "m²", "total rest area of the instance", table="garment"),
    _static("garments/settled", ("G",), "uint8", "bool", "1 when rest_vertices is the settled drape; 0 when every "
            "settle of the instance failed and rest_vertices is the builder's construction", table="garment"),
    # --- the sewing pattern of a pattern garment (shell garments: -1, NaN, no rows; docs/store.md)
    _static("garments/panel", ("n_garment_vertices",), "int32", "index",
            "panel of each vertex: its index in the design's panels (a welded seam vertex: the panel of its first "
            "face); -1 for a shell garment", minimum=-1, table="garment_vertex"),
    _static("garments/face_panel", ("n_garment_faces",), "int32", "index",
            "panel of each triangle (index in the design's panels); -1 for a shell garment", minimum=-1,
            table="garment_face"),
    _static("garments/rest_uv", ("n_garment_faces", 3, 2), "float32", "m",
            "2D rest coordinate of each triangle corner in its panel's flat pattern (the cloth's rest state; a "
            "welded seam vertex has one per panel); NaN for a shell garment", table="garment_face",
            finite="pattern"),
    _static("garments/stitches", ("n_stitches", 2), "int32", "index",
            "vertex pairs sewn together, local to the instance (0 .. V-1); a welded seam is one vertex and lists "
            "no pair", table="garment_stitch"),
    _static("garments/design", ("n_design_bytes",), "uint8", "utf-8",
            "the design record of a pattern garment, UTF-8 JSON: {program, seed, source, parameters, pattern "
            "(GarmentCode specification)}", table="garment_design"),
    # --- the fit-attribute model (factor analysis, paper 000)
    _static("fit/components", (3, "D"), "float32", "m", "factor loadings (in the features' unit)"),
    _static("fit/mean", ("D",), "float32", "m", "feature mean"),
    _static("fit/noise_variance", ("D",), "float32", "m²", "per-feature noise variance"),
    _static("fit/subsample", (3,), "int64", "1",
            "(rule version, N_g*, seed) of the even subsampling that picks the D features (datagen.targets.fit)",
            minimum=0),
)

DERIVED: dict[str, tuple[str, ...]] = {
    "joints": ("pose", "trans"),
    "anchor": ("pose", "trans"),
    "anchor_normal": ("pose",),
    "anchor_skin": ("pose",),
    "skin": ("pose",),
    "coarse_normal": ("coarse",),
    "joint_distance": ("coarse", "joints"),
    "body_vertices": ("pose", "trans"),
}
"""Per-frame arrays that are functions of the stored ones and the static groups (not stored; the
reader derives them with :mod:`datagen.features`), each with the stored per-frame arrays
it is computed from. ``joints`` is stored as well (it is the origin of the quantised positions)."""

ARRAYS: dict[str, ArraySpec] = {a.path: a for a in _ARRAY_LIST}
"""Every array of the packed store, by path."""

SAMPLE_TABLES = ("vertex_frame", "frame", "sim_frame", "sample")
"""Tables whose rows come from ``stage_sample``."""

STATIC_GROUPS: dict[str, str] = {
    "body": "the SMPL-format body model (no pose blend shapes)",
    "bodies": "body shape vectors",
    "motions": "motion tables",
    "garments": "garment instances: rest meshes and attributes, ragged by vertex_start / face_start",
    "fit": "the fit-attribute factor-analysis model",
}
"""Groups written once per store by ``StoreWriter.stage_static(group, ...)``; all are required."""

NAME_LISTS: dict[str, AttributeSpec] = {
    "split_names": AttributeSpec(type="list[str]", doc="names of samples/split codes (fixed: SPLIT_NAMES)"),
    "failure_names": AttributeSpec(type="list[str]", doc="names of samples/failure codes, 'ok' first"),
    "label_names": AttributeSpec(type="list[str]", doc="names of motion label codes", staged_with="motions"),
    "body_names": AttributeSpec(type="list[str]", doc="a name per row of bodies/betas", staged_with="bodies"),
    "garment_type_names": AttributeSpec(type="list[str]", doc="names of garments/type codes", staged_with="garments"),
    "material_names": AttributeSpec(type="list[str]", doc="names of garments/material codes", staged_with="garments"),
    "region_names": AttributeSpec(type="list[str]", doc="names of garments/region codes", staged_with="garments"),
}
"""Root attributes that name integer codes."""

ROOT_ATTRIBUTES: dict[str, AttributeSpec] = {
    "format": AttributeSpec(type="str", doc=f"always '{STORE_FORMAT}'"),
    "schema_version": AttributeSpec(type="int", doc="DATASET_SCHEMA_VERSION the store was written with"),
    "drape_version": AttributeSpec(type="str", doc="drape version that created the store"),
    "config": AttributeSpec(type="dict", doc="the resolved dataset configuration (JSON), without the settings that "
                                             "only spread the work (simulation.batch_size)"),
    "code_version": AttributeSpec(type="str", doc="digest of the code and library versions that made the samples "
                                                  "(datagen.generate.identity.code_version; '' when not recorded)"),
    "seed": AttributeSpec(type="int", doc="the dataset seed"),
    "sample_count": AttributeSpec(type="int", doc="number of samples (n_samples)"),
    "segment_length": AttributeSpec(type="int", doc="frames per segment in index/segments"),
    "complete": AttributeSpec(type="bool", doc="true once pack() has finished; set last, atomically"),
    "units": AttributeSpec(type="dict", doc="array path -> unit (as each array's 'unit' attribute)"),
    "checksums": AttributeSpec(type="dict", doc="array path -> {shard key: blake2b-128 digest} of every shard file, "
                                                "recorded at pack; validate proves the files unchanged with it"),
    "fit_attribute": AttributeSpec(type="bool", doc="whether the fit attribute α was fitted (the config's "
                                                   "fit_attribute); false: garments/alpha is NaN and fit/ has D = 0"),
    "fit_diagnostics": AttributeSpec(type="dict", doc="the factor analysis's health: training pairs, factors, "
                                                     "features at the noise-variance floor, α's spread across "
                                                     "subsample seeds, and the warnings given ({} without a fit)"),
    **NAME_LISTS,
}
"""Required root attributes of a packed store."""

IDENTITY_ATTRIBUTES = ("schema_version", "config", "code_version", "seed", "sample_count", "segment_length",
                       "failure_names")
"""Root attributes fixed when a store is created: reopening it with different values is refused."""
