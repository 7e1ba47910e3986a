"""Registers, stack frame and resident threads per SM of drape's warp kernels on a CUDA
architecture, from this machine: no GPU needed. Each module is compiled for ``--arch`` with NVRTC
(``wp.compile_aot_module``, into warp's kernel cache, where a later run on such a GPU finds it) and
the cubin's ``.nv.info`` records are read with pyelftools.

    python -m benchmarks kernel-registers [--arch 90] [--modules datagen.sim.kernels,...]

A kernel's registers per thread decide how many of its threads an SM keeps in flight (H100/H200,
sm_90: 65,536 registers and at most 2,048 threads per SM, warp's blocks of 256 threads); a stack
frame is local memory (spills, or a traversal stack that lives there). Needs ``pip install
pyelftools`` (the ``kernels`` extra)."""

from __future__ import annotations

import argparse
import importlib
import io
import math
import struct

MODULES = ("datagen.sim.kernels", "datagen.sim.projection_kernels", "datagen.sim.detection_kernels",
           "datagen.sim.newton_kernels", "datagen.sim.untangle_kernels", "datagen.sim.metrics")
REGISTERS_PER_SM = 65536
THREADS_PER_SM = 2048
BLOCK = 256
EIATTR_FRAME_SIZE, EIATTR_REGCOUNT = 0x11, 0x2F  # NVIDIA's cubin attribute ids (.nv.info)
EIFMT_NVAL, EIFMT_BVAL, EIFMT_HVAL, EIFMT_SVAL = 1, 2, 3, 4


def resident_threads(registers: int, block: int = BLOCK) -> int:
    """Threads of one kernel an sm_90 SM holds at once, as the register file allows (registers are
    given out per warp in units of 256)."""
    per_warp = math.ceil(registers * 32 / 256) * 256
    warps = REGISTERS_PER_SM // per_warp
    blocks = warps // (block // 32)
    return min(blocks * block, THREADS_PER_SM)


def cubin_kernels(data: bytes) -> dict[str, dict[int, int]]:
    """Per function symbol, its (symbol-indexed) .nv.info attributes with an 8-byte value."""
    from elftools.elf.elffile import ELFFile

    elf = ELFFile(io.BytesIO(data))
    names = [s.name for s in elf.get_section_by_name(".symtab").iter_symbols()]
    info = elf.get_section_by_name(".nv.info").data()
    out: dict[str, dict[int, int]] = {}
    p = 0
    while p + 2 <= len(info):
        fmt, attr = info[p], info[p + 1]
        if fmt == EIFMT_SVAL:
            size = struct.unpack_from("<H", info, p + 2)[0]
            if size == 8:
                sym, value = struct.unpack_from("<II", info, p + 4)
                out.setdefault(names[sym], {})[attr] = value
            p += 4 + size
        elif fmt in (EIFMT_BVAL, EIFMT_HVAL):
            p += 4
        elif fmt == EIFMT_NVAL:
            p += 2
        else:
            raise ValueError(f"unknown .nv.info record format {fmt:#x} at byte {p}")
    return out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--arch", type=int, default=90)
    ap.add_argument("--modules", default=",".join(MODULES))
    args = ap.parse_args(argv)
    import warp as wp

    wp.config.quiet = True
    wp.init()
    print(f"sm_{args.arch}: {REGISTERS_PER_SM} registers and {THREADS_PER_SM} threads per SM, blocks of {BLOCK}")
    print(f"{'registers':>9} {'frame B':>7} {'threads/SM':>10}  kernel")
    for name in args.modules.split(","):
        module = importlib.import_module(name)
        for path in wp.compile_aot_module(module, arch=args.arch, use_ptx=False):
            rows = []
            for symbol, attrs in cubin_kernels(path.read_bytes()).items():
                if symbol.endswith("_cuda_kernel_forward") and EIATTR_REGCOUNT in attrs:
                    regs = attrs[EIATTR_REGCOUNT]
                    rows.append((regs, attrs.get(EIATTR_FRAME_SIZE, 0), symbol.removesuffix("_cuda_kernel_forward")))
            print(f"# {name} ({path.parent.name})")
            for regs, frame, kernel in sorted(rows, reverse=True):
                print(f"{regs:9d} {frame:7d} {resident_threads(regs):10d}  {kernel}")
