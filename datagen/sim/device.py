"""The device a batch of scenes runs on: warp's name for it, warp kept quiet, its free memory, and
whether a batch fits (checked before anything is allocated).

:mod:`datagen.sim.scene` asks it before building a batch; ``drape generate`` asks it before a run
(:func:`available_ram`, :func:`warp_device`), the CLI and the export for :func:`quiet_warp`.
"""

from __future__ import annotations

import contextlib
import os

from datagen.errors import InputError, SimulationError

BYTES_PER_GARMENT_VERTEX = 6_000
"""Device memory a garment vertex takes in a batch, contact buffers included [bytes]: measured 3.4 kB
(13.5 MB per scene of 3,974 vertices at 64 and 256 scenes on an H100, 18 MB alone), with room for
the contact buffers to grow."""

BYTES_PER_BODY_VERTEX = 400
"""Device memory a body vertex takes (posed copies, the body's mesh with its tree and winding-number
data) [bytes]; an upper bound since the part meshes went (2026-11-27)."""

MEMORY_ADVICE = ("Simulate fewer scenes at once (the dataset config's simulation.batch_size), coarser garments "
                 "(a larger garment_edge_length) or use a device with more memory.")


def quiet_warp(level: int = 30, *, initialise: bool = False) -> None:
    """Keep warp's initialisation banner and per-module load lines off the console: only messages
    of ``level`` or worse (logging's numbers: 30 warnings, 40 errors) pass. Recent warp versions
    have ``config.log_level``, older ones ``config.quiet``. With ``initialise``, warp is initialised
    now with the process's stderr silenced: its native library prints a "could not load the NVIDIA
    CUDA driver" notice on every machine without a GPU, which no setting turns off (a command asked
    for ``--device cuda`` there says so itself)."""
    import warp as wp

    if hasattr(wp.config, "log_level"):
        wp.config.log_level = max(wp.config.log_level, level)
    else:
        wp.config.quiet = True
    if initialise:
        with _native_stderr_silenced():
            wp.init()


@contextlib.contextmanager
def _native_stderr_silenced():
    """File descriptor 2 pointed at /dev/null for the block: what native libraries print there
    (warp's CUDA-driver notices) is dropped; Python's own errors are raised as usual."""
    import sys

    sys.stderr.flush()
    saved = os.dup(2)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 2)
            yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)


def warp_device(device: str | None) -> str:
    """warp's name for ``device`` (``cpu``, ``cuda``, ``cuda:N``), or an :class:`InputError` that says
    what is wrong and what to do (a CUDA device on a machine without one, a name warp does not know)."""
    import warp as wp

    try:
        with _native_stderr_silenced():  # warp's C code prints CUDA-driver errors of its own on the way
            return str(wp.get_device(device))
    except (RuntimeError, ValueError) as exc:  # warp: unknown or absent device
        if str(device).startswith("cuda"):
            raise InputError(f"--device {device}: no CUDA device is usable here (warp: {exc}); use --device cpu, or run "
                             "on a machine with an NVIDIA GPU and driver") from None
        raise InputError(f"--device {device!r} is not a warp device; use cpu or cuda (cuda:N)") from None


def device_free_bytes(device: str | None) -> int | None:
    """Free memory of ``device`` [bytes]: a CUDA device's free memory, the CPU's available RAM;
    None when it cannot be told."""
    import warp as wp

    dev = wp.get_device(device)
    if dev.is_cuda:
        return int(dev.free_memory)
    return available_ram()


def available_ram() -> int | None:
    """Host memory that can be had without swapping [bytes]; None when it cannot be told."""
    try:  # Linux: what can be had without swapping (page cache that can be dropped included)
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return None


def check_device_memory(arrays: list, device: str | None) -> int:
    """Refuse a batch of :class:`~datagen.sim.scene.SceneArrays` whose estimated memory exceeds what
    ``device`` has free, with the figures and what to do (before anything is allocated); returns the
    estimate [bytes]."""
    need = sum(len(a.garment_vertices) * BYTES_PER_GARMENT_VERTEX + a.body_frames.shape[1] * BYTES_PER_BODY_VERTEX
               for a in arrays)
    free = device_free_bytes(device)
    if free is not None and need > free:
        largest = max(len(a.garment_vertices) for a in arrays)
        raise SimulationError(
            f"a batch of {len(arrays)} scenes (largest garment {largest:,} vertices) needs about {need / 2**20:,.0f} MiB "
            f"on device {device or 'default'}, which has {free / 2**20:,.0f} MiB free. {MEMORY_ADVICE}")
    return need


def torch_cuda(device: str | None) -> bool:
    """Whether warp ``device`` is a CUDA device that torch can use as well."""
    if device is None or not str(device).startswith("cuda"):
        return False
    import torch

    return torch.cuda.is_available()
