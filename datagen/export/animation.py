"""The arrays of one animated scene (a body and a garment over T frames) and where they come from.

:class:`Animation` is what the exporters draw and write. Three sources make one:

- a dataset store sample (:func:`from_store`): the simulated garment (``detail``), the posed
  body, the garment instance's rest mesh and region labels, the pose and translation, and, for a
  UsdSkel rig, the store's body model (rest shape from the sample's betas, skinning weights);
- a ``drape simulate`` result (:func:`from_npz`): the plain arrays below as the simulator recorded
  them (the body it collided with, the poses, the garment's rest mesh and panels, the body's rig),
  with the run's metrics, failure and the names and seeds it was made from; nothing is made again;
- plain arrays (:func:`from_npz`, an ``.npz`` with ``garment_vertices``), e.g. a model's
  prediction: ``garment_vertices`` [T, V, 3], ``garment_faces`` [F, 3], ``body_vertices``
  [T, B, 3], ``body_faces`` [Fb, 3], ``fps``; optional ``region`` [V], ``region_names`` [R]
  (strings), ``garment_rest`` [V, 3], and for a rig ``pose`` [T, 24, 3], ``trans`` [T, 3],
  ``rest_joints`` [24, 3], optionally ``rest_body_vertices`` [B, 3] and ``skin_weights`` [B, 24].

:func:`load_animation` picks the loader from the path (a store directory or an ``.npz``).
"""

from __future__ import annotations

import logging
import os
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from datagen.errors import InputError
from datagen.export.usd import SkeletonAnimation

__all__ = ["Animation", "check_sample", "from_npz", "from_store", "load_animation", "parse_frames", "read_npz"]

logger = logging.getLogger(__name__)

DEFAULT_FPS = 30.0
"""Frame rate of ``drape simulate`` and of the dataset presets, used where a source does not say."""


@dataclass
class Animation:
    """A body and a garment over the same T frames, plus what is known about them.

    Attributes:
        body_vertices: posed body [T, B, 3] (m), float32.
        body_faces: body triangles [Fb, 3].
        garment_vertices: garment [T, V, 3] (m), float32.
        garment_faces: garment triangles [F, 3].
        fps: frames per second.
        region: region code per garment vertex [V], or None.
        region_names: the names of the region codes, or None.
        garment_rest: the garment's rest shape [V, 3] (m), or None (needed for stretch).
        skeleton: the body's rig and motion, or None.
        metadata: what the arrays are (source, sample, split, garment, body, motion, failure, ...).
        title: a one-line description for pictures.
        frame_numbers: the source's frame number of each of these frames [T] (None: 0 .. T-1).
        garment_st: texture coordinates (m): per triangle corner [F, 3, 2] (a pattern garment's flat
            panels) or per vertex [V, 2] (a shell's material uv), or None.
        garment_panel: the pattern panel of every triangle [F], or None (a shell garment).
        panel_names: the names of the panels, or None.
    """

    body_vertices: np.ndarray
    body_faces: np.ndarray
    garment_vertices: np.ndarray
    garment_faces: np.ndarray
    fps: float
    region: np.ndarray | None = None
    region_names: tuple[str, ...] | None = None
    garment_rest: np.ndarray | None = None
    skeleton: SkeletonAnimation | None = None
    metadata: dict[str, Any] = field(default_factory=dict)
    title: str = ""
    frame_numbers: np.ndarray | None = None
    garment_st: np.ndarray | None = None
    garment_panel: np.ndarray | None = None
    panel_names: tuple[str, ...] | None = None

    @property
    def frame_count(self) -> int:
        return int(self.garment_vertices.shape[0])

    @property
    def source_frames(self) -> np.ndarray:
        """The source's frame number of each frame."""
        return np.arange(self.frame_count) if self.frame_numbers is None else np.asarray(self.frame_numbers)

    def frames(self, index: np.ndarray) -> Animation:
        """The animation restricted to frames ``index`` (of these arrays)."""
        index = np.asarray(index, dtype=np.int64)
        sk = self.skeleton
        if sk is not None:
            sk = replace(sk, poses=np.asarray(sk.poses)[index], trans=np.asarray(sk.trans)[index])
        return replace(self, body_vertices=self.body_vertices[index], garment_vertices=self.garment_vertices[index],
                       skeleton=sk, frame_numbers=self.source_frames[index])

    def write_usd(self, path: str | os.PathLike, *, skeleton: bool = False, normals: bool = True,
                  garment_colors: np.ndarray | None = None, garment_values: tuple | None = None) -> Path:
        """:func:`~datagen.export.usd.write_animation_usd` of these arrays."""
        from datagen.export.usd import write_animation_usd

        if skeleton and self.skeleton is None:
            raise InputError("this source has no pose and joints to build a skeleton from")
        return write_animation_usd(path, self.body_vertices, self.body_faces, self.garment_vertices,
                                   self.garment_faces, self.fps, region=self.region, region_names=self.region_names,
                                   skeleton=self.skeleton if skeleton else None, metadata=self.metadata,
                                   normals=normals, garment_colors=garment_colors, garment_values=garment_values,
                                   garment_st=self.garment_st, garment_panel=self.garment_panel,
                                   panel_names=self.panel_names)


# ------------------------------------------------------------------------------------- stores


def check_sample(store, sample) -> int:
    """``sample`` as a valid sample index of ``store``, else :class:`InputError` naming the range."""
    n = len(store)
    if isinstance(sample, bool) or not isinstance(sample, (int, np.integer)):
        raise InputError(f"sample id must be an integer, got {sample!r}")
    i = int(sample)
    if not 0 <= i < n:
        valid = f"0 .. {n - 1}" if n else "none: the store is empty"
        raise InputError(f"sample {sample} is not in store {store.path}: valid sample ids are {valid}")
    return i


def parse_frames(spec: str | None, frame_count: int) -> np.ndarray:
    """Frame indices from ``A:B[:step]`` (Python slice syntax; empty parts allowed) or ``N``.

    Raises:
        InputError: a malformed spec, or frames outside ``0 .. frame_count - 1``.
    """
    if frame_count < 1:
        raise InputError("the sample has no frames")
    if spec is None or spec.strip() in ("", ":"):
        return np.arange(frame_count)
    parts = spec.split(":")
    try:
        nums = [int(p) if p.strip() else None for p in parts]
    except ValueError:
        raise InputError(f"frames must be N or A:B[:step] with integers, got {spec!r}") from None
    if len(parts) == 1:
        k = nums[0]
        if k is None or not 0 <= k < frame_count:
            raise InputError(f"--frame {spec} is out of range: valid frames are 0 .. {frame_count - 1} (count from 0; "
                             "negative numbers are not read as from the end)")
        return np.array([k])
    if len(parts) > 3:
        raise InputError(f"frames must be N or A:B[:step], got {spec!r}")
    a, b = nums[0], nums[1]
    step = nums[2] if len(nums) == 3 else None
    if step is not None and step <= 0:
        raise InputError(f"the frame step must be positive, got {step}")
    for v in (a, b):
        if v is not None and not 0 <= v <= frame_count:
            raise InputError(f"frames {spec} are out of range: valid frames are 0 .. {frame_count - 1}")
    index = np.arange(frame_count)[slice(a, b, step)]
    if index.size == 0:
        raise InputError(f"frames {spec} select no frame of 0 .. {frame_count - 1}")
    return index


def _name(names: tuple[str, ...], code: int) -> str:
    return names[code] if 0 <= code < len(names) else f"code {code}"


def from_store(store, sample: int, *, frames: np.ndarray | None = None, skeleton: bool = False,
               allow_failed: bool = True) -> Animation:
    """Sample ``sample`` of ``store`` (a path or an open :class:`~datagen.store.DatasetStore`).

    Args:
        store: the store.
        sample: sample index.
        frames: recorded frames to read (default all).
        skeleton: also read the body model to build a :class:`SkeletonAnimation`.
        allow_failed: a failed sample that has frames is loaded with a warning (else refused).

    Raises:
        InputError: an unknown sample id (the message gives the valid range), or a sample with no
            recorded frames (failed samples keep only their metrics).
    """
    from datagen.store import open_store

    if isinstance(store, (str, os.PathLike)):
        store = open_store(store)
    i = check_sample(store, sample)
    sc = store.scalars(i)
    names = store.names
    failure = int(sc["failure"])
    T = store.frame_count(i)
    if failure:
        what = (f"sample {i} failed ({_name(names['failure_names'], failure)} at simulated frame "
                f"{int(sc['failure_frame'])})")
        if T == 0:
            raise InputError(f"{what} and has no recorded frames (a failed sample keeps only its metrics); "
                             "nothing to export")
        if not allow_failed:
            raise InputError(what)
        logger.warning("%s: exporting its %d recorded frames anyway", what, T)
    index = np.arange(T) if frames is None else np.asarray(frames, dtype=np.int64)
    want = ["detail", "body_vertices", "pose", "trans"]
    x = store.frames(i, index, names=want)
    g = int(sc["garment"])
    garment = store.garment(g)
    b, m = int(sc["body"]), int(sc["motion"])
    motions = store.motions()
    gtype = _name(names["garment_type_names"], int(garment["type"]))
    body_name = _name(names["body_names"], b)
    label = _name(names["label_names"], int(motions["label"][m]))
    split = _name(names["split_names"], int(sc["split"]))
    fps = float(store.config.get("fps", DEFAULT_FPS))
    meta = {"source": str(store.path), "sample": i, "split": split, "garment_instance": g, "garment_type": gtype,
            "garment_seed": int(garment["seed"]), "material": _name(names["material_names"], int(garment["material"])),
            "alpha": [float(a) for a in garment["alpha"]], "body": body_name, "body_index": b,
            "motion": label, "motion_seed": int(motions["seed"][m]), "motion_index": m,
            "failure": _name(names["failure_names"], failure), "frames": T, "fps": fps}
    body_faces = store.read("body/faces")
    sk = None
    if skeleton:
        model = store.body_model()
        betas = store.betas()[b].astype(np.float64)
        S = len(betas)
        rest_v = model["v_template"].astype(np.float64) + np.einsum("vcs,s->vc", model["shapedirs"][:, :, :S]
                                                                    .astype(np.float64), betas)
        rest_j = model["J_regressor"].astype(np.float64) @ rest_v
        sk = SkeletonAnimation(poses=x["pose"], trans=x["trans"], rest_joints=rest_j, parents=model["parents"],
                               rest_vertices=rest_v, weights=model["weights"])
    pattern = garment["design"] is not None
    if pattern:
        meta |= {"design_program": str(garment["design"].get("program")), "design_seed": int(garment["design"]["seed"])}
        # panel p's name: the region name of its vertices (a pattern garment's regions are its panels)
        first = {int(p): int(r) for p, r in zip(garment["panel"][::-1], garment["region"][::-1], strict=True)}
        panels = [_name(names["region_names"], first[p]) if p in first else f"panel {p}"
                  for p in range(int(garment["face_panel"].max()) + 1)]
    title = f"sample {i} ({split}): {gtype} on {body_name}, {label}" + (
        f" [failed: {meta['failure']}]" if failure else "")
    return Animation(body_vertices=x["body_vertices"], body_faces=body_faces, garment_vertices=x["detail"],
                     garment_faces=garment["faces"], fps=fps, region=garment["region"],
                     region_names=tuple(names["region_names"]), garment_rest=garment["built_vertices"], skeleton=sk,
                     metadata=meta, title=title, frame_numbers=None if frames is None else index,
                     garment_st=garment["rest_uv"] if pattern else garment["uv"],
                     garment_panel=garment["face_panel"] if pattern else None,
                     panel_names=tuple(panels) if pattern else None)


# ------------------------------------------------------------------------------------- npz


def _scalar(d, key: str, default=None):
    if key not in d:
        return default
    v = np.asarray(d[key])
    return v.item() if v.ndim == 0 else v


def read_npz(path: str | os.PathLike, what: str) -> dict[str, np.ndarray]:
    """Every array of the NumPy ``.npz`` archive at ``path`` (plain arrays only: a pickled object is
    refused, never loaded), or :class:`InputError` saying what the file is; ``what`` names the file's
    role in messages (``"prediction file"``)."""
    import zipfile

    path = Path(path)
    if not path.is_file():
        raise InputError(f"{what} {path} does not exist")
    if not zipfile.is_zipfile(path):
        raise InputError(f"{what} {path} is not a NumPy .npz file (an .npz is a zip archive of .npy arrays; this "
                         "file is not a zip archive): give the .npz that drape or numpy.savez wrote")
    out: dict[str, np.ndarray] = {}
    try:
        with np.load(path, allow_pickle=False) as d:
            for key in d.files:
                try:
                    out[key] = d[key]
                except ValueError as exc:
                    if "pickle" not in str(exc):
                        raise
                    raise InputError(f"{what} {path}: array {key!r} holds Python objects, which drape does not "
                                     "load (loading them could run code); save plain numeric arrays") from None
    except InputError:
        raise
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
        raise InputError(f"{what} {path} is a damaged .npz file ({' '.join(str(exc).split())})") from None
    return out


def from_npz(path: str | os.PathLike, *, fps: float | None = None) -> Animation:
    """An ``.npz`` of plain arrays or a ``drape simulate`` result (see the module docstring);
    ``fps`` is for files without one (default 30)."""
    path = Path(path)
    d = read_npz(path, "animation file")
    if "garment_vertices" in d:
        return _from_arrays(path, d, fps)
    if {"positions", "faces", "motion", "body", "garment"} <= set(d):
        raise InputError(f"{path} is a 'drape simulate' result from an older drape, which did not record the body "
                         "and the garment's panels: run drape simulate again to export it")
    raise InputError(f"{path} holds neither plain arrays ('garment_vertices', 'body_vertices', ...) nor a "
                     f"'drape simulate' result; it has {sorted(d)}")


_RUN_KEYS = ("garment", "garment_seed", "body", "motion", "motion_seed", "recorded_from", "motion_from")
"""What a ``drape simulate`` result records of its run, carried into the animation's metadata."""


def _from_arrays(path: Path, d: dict, fps: float | None) -> Animation:
    missing = [k for k in ("garment_vertices", "garment_faces", "body_vertices", "body_faces") if k not in d]
    if missing:
        raise InputError(f"{path} lacks {missing}; plain-array files need garment_vertices, garment_faces, "
                         "body_vertices, body_faces (and fps)")
    fps = float(_scalar(d, "fps", fps if fps is not None else DEFAULT_FPS))
    sk = None
    if {"pose", "trans", "rest_joints"} <= set(d):
        from datagen.body.skeleton import SMPL_PARENTS

        sk = SkeletonAnimation(poses=d["pose"], trans=d["trans"], rest_joints=d["rest_joints"],
                               parents=d.get("parents", np.array(SMPL_PARENTS)),
                               rest_vertices=d.get("rest_body_vertices"), weights=d.get("skin_weights"))
    names = tuple(str(n) for n in d["region_names"]) if "region_names" in d else None
    meta = {"source": str(path), "fps": fps, "frames": int(len(d["garment_vertices"]))}
    title = path.name
    if "garment" in d:  # a drape simulate result: what it was made of and how it went
        run = {k: _scalar(d, k) for k in _RUN_KEYS if k in d}
        meta.update({("garment_type" if k == "garment" else k): v for k, v in run.items()})
        failure = str(_scalar(d, "failure", ""))
        meta["failure"] = failure or "ok"
        if failure:
            logger.warning("%s: the simulation failed (%s: %s); exporting its recorded frames anyway", path, failure,
                           _scalar(d, "failure_message", ""))
        if "config" in d:
            meta["run_config"] = str(_scalar(d, "config"))
        title = (f"{path.name}: {run.get('garment')} on {run.get('body')}, {run.get('motion')}"
                 + (f" [failed: {failure}]" if failure else ""))
    return Animation(body_vertices=np.asarray(d["body_vertices"], np.float32), body_faces=d["body_faces"],
                     garment_vertices=np.asarray(d["garment_vertices"], np.float32), garment_faces=d["garment_faces"],
                     fps=fps, region=d.get("region"), region_names=names, garment_rest=d.get("garment_rest"),
                     skeleton=sk, metadata=meta, title=title)


def load_animation(source: str | os.PathLike, sample: int | None = None, *, frames: np.ndarray | None = None,
                   skeleton: bool = False, **npz_options) -> Animation:
    """A store sample (``source`` a store directory, ``sample`` required) or an ``.npz``."""
    source = Path(source)
    if source.is_dir():
        if sample is None:
            raise InputError(f"{source} is a store: say which sample with --sample ID")
        return from_store(source, sample, frames=frames, skeleton=skeleton)
    if source.suffix.lower() == ".npz":
        if sample is not None:
            raise InputError(f"{source} holds one scene; --sample is for stores")
        anim = from_npz(source, **npz_options)
        return anim if frames is None else anim.frames(frames)
    if not source.exists():
        raise InputError(f"{source} does not exist")
    raise InputError(f"{source} is neither a store directory nor an .npz file")
