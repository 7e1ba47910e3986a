"""Pictures of an animation: one frame to PNG, a clip to GIF or MP4, offscreen on the CPU.

Frames are drawn by the shared painter's-algorithm renderer of :mod:`datagen.body.render`
(matplotlib, no display): the body one-sided in a skin grey, the garment two-sided (its inside
darker) in one colour, by region (with a legend), or coloured by a per-vertex quantity with a
colour bar:

- ``stretch``: per vertex, the mean over its edges of (edge length / rest edge length) - 1, in
  percent; needs the garment's rest shape (stores have it);
- ``body-distance``: signed distance from each garment vertex to the posed body surface in mm
  (negative inside the body; a warp mesh query with winding-number sign);
- ``error``: distance of each predicted vertex from the simulated one in mm; needs a prediction
  (the predicted garment is then drawn).

The camera is orthographic, at an azimuth around the vertical axis (``VIEWS`` or degrees), and
follows the scene: every frame is centred on what it shows, at one scale for the whole clip. The
colour range is fixed over the clip (robust percentiles) unless given. Files are written to a
temporary name and renamed. GIFs are written with Pillow (matplotlib's own dependency); MP4 needs
``imageio-ffmpeg``.
"""

from __future__ import annotations

import logging
import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from datagen.body.render import VIEWS, MeshLayer, pyplot, shade_polygons, view_rotation
from datagen.errors import InputError, MissingDependencyError
from datagen.export.animation import Animation
from datagen.sim.device import quiet_warp
from datagen.export.usd import GARMENT_COLOR, REGION_COLORS
from datagen.files import atomic_output, check_output_path
from datagen.geometry.topology import unique_edges

__all__ = ["CLIP_SUFFIXES", "COLOR_BY", "IMAGE_SUFFIXES", "body_distance", "parse_size", "parse_view",
           "render_clip", "render_frame", "vertex_stretch"]

logger = logging.getLogger(__name__)

COLOR_BY = ("none", "region", "stretch", "body-distance", "error")
IMAGE_SUFFIXES = (".png",)
CLIP_SUFFIXES = (".gif", ".mp4")
BODY_COLOR = (0.78, 0.74, 0.70)
DPI = 100
GARMENT_DEPTH_BIAS = 0.02
"""Sort depth added to the garment's camera-facing faces [m], so it is drawn over the body it lies on."""
DEFAULT_SIZE = (512, 640)

_QUANTITIES = {  # colour-by -> (colour bar label, colormap)
    "stretch": ("stretch: edge length / rest - 1 (%)", "coolwarm"),
    "body-distance": ("distance to the body surface (mm), < 0 inside", "viridis"),
    "error": ("prediction error (mm)", "magma"),
}


def parse_view(view: str | float) -> float:
    """Azimuth in degrees from a view name (``front``, ``side``, ``back``, ``three-quarter``) or a number."""
    if isinstance(view, (int, float)):
        return float(view)
    if view in VIEWS:
        return VIEWS[view]
    try:
        azimuth = float(view)
    except ValueError:
        raise InputError(f"unknown view {view!r}: give one of {', '.join(VIEWS)} or an azimuth in degrees") from None
    if not math.isfinite(azimuth):
        raise InputError(f"--view {view!r} is not a finite azimuth: give one of {', '.join(VIEWS)} or degrees")
    return azimuth


def parse_size(size: str | tuple[int, int]) -> tuple[int, int]:
    """(width, height) in pixels from ``WxH``; both even and within 64 .. 4096."""
    if isinstance(size, str):
        try:
            w, h = (int(x) for x in size.lower().split("x"))
        except ValueError:
            raise InputError(f"size must be WIDTHxHEIGHT in pixels, e.g. 512x640, got {size!r}") from None
    else:
        w, h = size
    if not (64 <= w <= 4096 and 64 <= h <= 4096) or w % 2 or h % 2:
        raise InputError(f"size must be two even numbers of pixels within 64 .. 4096, got {w}x{h}")
    return w, h


# ------------------------------------------------------------------------------------- quantities


def vertex_stretch(vertices: np.ndarray, faces: np.ndarray, rest: np.ndarray) -> np.ndarray:
    """Per-vertex mean over incident edges of (length / rest length) - 1, [T, V] for [T, V, 3]."""
    e = unique_edges(faces)
    rest = np.asarray(rest, dtype=np.float64)
    rest_len = np.linalg.norm(rest[e[:, 1]] - rest[e[:, 0]], axis=-1)
    v = np.asarray(vertices, dtype=np.float64)
    ratio = np.linalg.norm(v[:, e[:, 1]] - v[:, e[:, 0]], axis=-1) / np.maximum(rest_len, 1e-12) - 1.0  # [T, E]
    V = v.shape[1]
    count = np.bincount(e.reshape(-1), minlength=V).astype(np.float64)
    out = np.zeros((len(v), V))
    for k in range(len(v)):
        out[k] = np.bincount(e[:, 0], ratio[k], V) + np.bincount(e[:, 1], ratio[k], V)
    return out / np.maximum(count, 1)


def body_distance(vertices: np.ndarray, body_vertices: np.ndarray, body_faces: np.ndarray) -> np.ndarray:
    """Signed distance [T, V] (m) from garment vertices [T, V, 3] to the body surfaces [T, B, 3];
    negative inside the body."""
    from datagen.geometry.queries import mesh_signed_distance, warp_mesh

    quiet_warp()
    out = np.zeros(vertices.shape[:2], dtype=np.float64)
    for k in range(len(vertices)):
        out[k] = mesh_signed_distance(warp_mesh(body_vertices[k], body_faces), vertices[k], 10.0)
    return out


# ------------------------------------------------------------------------------------- renderer


@dataclass
class _Colouring:
    values: np.ndarray | None  # [T, V] in display units
    label: str = ""
    cmap: str = "viridis"
    vmin: float = 0.0
    vmax: float = 1.0


def _colouring(anim: Animation, color_by: str, prediction: np.ndarray | None,
               value_range: tuple[float, float] | None) -> _Colouring:
    if color_by not in COLOR_BY:
        raise InputError(f"unknown colouring {color_by!r}; choose from {', '.join(COLOR_BY)}")
    if color_by == "error" and prediction is None:
        raise InputError("--color-by error needs a prediction (--prediction PRED.npz) to compare with the simulation")
    if color_by == "region" and anim.region is None:
        raise InputError("this source has no garment regions to colour by")
    if color_by not in _QUANTITIES:
        return _Colouring(None)
    garment = anim.garment_vertices if prediction is None else prediction
    if color_by == "stretch":
        if anim.garment_rest is None:
            raise InputError("--color-by stretch needs the garment's rest shape, which this source does not have")
        values = 100.0 * vertex_stretch(garment, anim.garment_faces, anim.garment_rest)
    elif color_by == "body-distance":
        values = 1000.0 * body_distance(garment, anim.body_vertices, anim.body_faces)
    else:
        values = 1000.0 * np.linalg.norm(np.asarray(prediction, np.float64) - anim.garment_vertices, axis=-1)
    label, cmap = _QUANTITIES[color_by]
    if value_range is not None:
        lo, hi = value_range
    elif color_by == "stretch":
        hi = max(float(np.percentile(np.abs(values), 99)), 0.1)
        lo = -hi
    elif color_by == "error":
        lo, hi = 0.0, max(float(np.percentile(values, 99)), 0.1)
    else:
        lo, hi = (float(x) for x in np.percentile(values, [1, 99]))
    if not hi > lo:
        hi = lo + 1.0
    return _Colouring(values, label, cmap, lo, hi)


class _FrameDrawer:
    """One matplotlib figure reused for every frame of a clip."""

    def __init__(self, anim: Animation, azimuth: float, size: tuple[int, int], color_by: str,
                 prediction: np.ndarray | None, value_range: tuple[float, float] | None):
        self.plt = pyplot()
        from matplotlib.collections import PolyCollection

        self.anim, self.azimuth = anim, azimuth
        self.garment = anim.garment_vertices if prediction is None else np.asarray(prediction, np.float32)
        self.colouring = _colouring(anim, color_by, prediction, value_range)
        self.color_by = color_by
        w, h = size
        self.fig = self.plt.figure(figsize=(w / DPI, h / DPI), dpi=DPI, facecolor="white")
        bar = self.colouring.values is not None
        self.ax = self.fig.add_axes((0.02, 0.02, 0.76 if bar else 0.96, 0.90))
        self.ax.set_aspect("equal")
        self.ax.axis("off")
        self.collection = PolyCollection(np.zeros((0, 3, 2)), linewidths=0.25)
        self.ax.add_collection(self.collection)
        self.text = self.fig.text(0.5, 0.965, "", ha="center", va="center", fontsize=max(6, h // 90))
        faces = np.asarray(anim.garment_faces)
        if bar:
            import matplotlib as mpl

            c = self.colouring
            self.norm = mpl.colors.Normalize(c.vmin, c.vmax, clip=True)
            self.cmap = mpl.colormaps[c.cmap]
            cax = self.fig.add_axes((0.82, 0.12, 0.035, 0.7))
            cb = self.fig.colorbar(mpl.cm.ScalarMappable(norm=self.norm, cmap=self.cmap), cax=cax)
            cb.set_label(c.label, fontsize=max(6, h // 100))
            cb.ax.tick_params(labelsize=max(6, h // 110))
        elif color_by == "region":
            from matplotlib.patches import Patch

            r = np.asarray(anim.region)[faces]
            self.face_colors = np.asarray(REGION_COLORS)[np.where(r[:, 1] == r[:, 2], r[:, 1], r[:, 0])
                                                         % len(REGION_COLORS)]
            names = anim.region_names or ()
            present = np.unique(anim.region)
            handles = [Patch(color=REGION_COLORS[k % len(REGION_COLORS)],
                             label=names[k] if k < len(names) else f"region {k}") for k in present]
            self.fig.legend(handles=handles, loc="lower right", fontsize=max(6, h // 110), frameon=False)
        else:
            self.face_colors = np.asarray(GARMENT_COLOR)
        # one scale for the clip, fitted to the axes' shape; each frame centred on what it shows
        rot = view_rotation(azimuth)
        self.centres, hx, hy = [], 0.0, 0.0
        for k in range(anim.frame_count):
            p = np.concatenate([anim.body_vertices[k], self.garment[k]]).astype(np.float64) @ rot.T
            lo, hi = p.min(0), p.max(0)
            self.centres.append((lo + hi) / 2)
            hx, hy = max(hx, float(hi[0] - lo[0]) / 2), max(hy, float(hi[1] - lo[1]) / 2)
        _, _, aw, ah = self.ax.get_position(original=True).bounds
        aspect = (aw * w) / (ah * h)  # axes width / height in pixels
        self.half_y = max(hy, hx / aspect) * 1.04
        self.half_x = self.half_y * aspect

    def garment_colors(self, k: int) -> np.ndarray:
        c = self.colouring
        if c.values is None:
            return self.face_colors
        face_values = c.values[k][np.asarray(self.anim.garment_faces)].mean(axis=1)
        return self.cmap(self.norm(face_values))[:, :3]

    def draw(self, k: int) -> np.ndarray:
        """Frame ``k`` as an RGB image [H, W, 3] uint8."""
        a = self.anim
        layers = [MeshLayer(a.body_vertices[k], a.body_faces, BODY_COLOR),
                  MeshLayer(self.garment[k], a.garment_faces, self.garment_colors(k), two_sided=True,
                            depth_bias=GARMENT_DEPTH_BIAS)]
        polys, rgb = shade_polygons(layers, self.azimuth, ambient=0.3, absolute=True)
        self.collection.set_verts(polys)
        self.collection.set_facecolor(rgb)
        self.collection.set_edgecolor(rgb)
        c = self.centres[k]
        self.ax.set_xlim(c[0] - self.half_x, c[0] + self.half_x)
        self.ax.set_ylim(c[1] - self.half_y, c[1] + self.half_y)
        self.text.set_text(f"{a.title}, frame {int(a.source_frames[k])}" if a.title else
                           f"frame {int(a.source_frames[k])}")
        self.fig.canvas.draw()
        return np.asarray(self.fig.canvas.buffer_rgba())[..., :3].copy()

    def close(self) -> None:
        self.plt.close(self.fig)


def _check_prediction(anim: Animation, prediction: np.ndarray | None) -> np.ndarray | None:
    if prediction is None:
        return None
    p = np.asarray(prediction)
    if p.shape != anim.garment_vertices.shape:
        raise InputError(f"the prediction has shape {p.shape}; the garment's frames are {anim.garment_vertices.shape}")
    if not np.isfinite(p).all():
        raise InputError("the prediction has non-finite values")
    return p.astype(np.float32)


def render_frame(anim: Animation, path: str | os.PathLike, *, frame: int = 0, view: str | float = "front",
                 size: str | tuple[int, int] = DEFAULT_SIZE, color_by: str = "none",
                 prediction: np.ndarray | None = None, value_range: tuple[float, float] | None = None) -> Path:
    """Write frame ``frame`` (of ``anim``'s frames) as a PNG of ``size`` (W, H) pixels."""
    path = check_output_path(path, IMAGE_SUFFIXES, "picture")
    if not 0 <= frame < anim.frame_count:
        raise InputError(f"frame {frame} is out of range: valid frames are 0 .. {anim.frame_count - 1}")
    one = anim.frames(np.array([frame]))
    pred = _check_prediction(anim, prediction)
    drawer = _FrameDrawer(one, parse_view(view), parse_size(size), color_by,
                          None if pred is None else pred[[frame]], value_range)
    try:
        image = drawer.draw(0)
    finally:
        drawer.close()
    from PIL import Image

    with atomic_output(path) as tmp:
        Image.fromarray(image).save(tmp, format="PNG")
    logger.debug("wrote %s: frame %d, %dx%d pixels", path, int(one.source_frames[0]), image.shape[1], image.shape[0])
    return path


def render_clip(anim: Animation, path: str | os.PathLike, *, view: str | float = "front",
                size: str | tuple[int, int] = DEFAULT_SIZE, color_by: str = "none", fps: float | None = None,
                prediction: np.ndarray | None = None, value_range: tuple[float, float] | None = None) -> Path:
    """Write every frame of ``anim`` as a GIF or MP4 (by suffix) at ``fps`` (default ``anim.fps``)."""
    path = check_output_path(path, CLIP_SUFFIXES, "clip")
    fps = float(anim.fps if fps is None else fps)
    if not (np.isfinite(fps) and fps > 0):
        raise InputError(f"fps must be positive, got {fps}")
    mp4 = path.suffix.lower() == ".mp4"
    if mp4:
        try:
            import imageio_ffmpeg
        except ImportError:
            raise MissingDependencyError("writing MP4 clips needs the Python package 'imageio-ffmpeg', which is not "
                                         "installed. Install it with: pip install imageio-ffmpeg (or pip install "
                                         "'drape[render]'), or write a .gif") from None
    pred = _check_prediction(anim, prediction)
    w, h = parse_size(size)
    drawer = _FrameDrawer(anim, parse_view(view), (w, h), color_by, pred, value_range)
    try:
        with atomic_output(path) as tmp:
            if mp4:
                writer = imageio_ffmpeg.write_frames(str(tmp), (w, h), fps=fps, codec="libx264", quality=7,
                                                     pix_fmt_out="yuv420p", macro_block_size=2)
                writer.send(None)
                try:
                    for k in range(anim.frame_count):
                        writer.send(np.ascontiguousarray(drawer.draw(k)))
                finally:
                    writer.close()
            else:
                from PIL import Image

                images = [Image.fromarray(drawer.draw(k)).quantize(colors=255, method=Image.Quantize.MEDIANCUT)
                          for k in range(anim.frame_count)]
                images[0].save(tmp, format="GIF", save_all=True, append_images=images[1:],
                               duration=max(20, round(1000.0 / fps)), loop=0, optimize=False)
    finally:
        drawer.close()
    logger.debug("wrote %s: %d frames at %g fps, %dx%d pixels", path, anim.frame_count, fps, w, h)
    return path
