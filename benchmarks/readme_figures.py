"""Every figure README.md quotes, re-measured on this machine by the command behind it, beside what
README says: ``python -m benchmarks readme-figures --device cpu|cuda --out DIR``.

Each figure is a record (:class:`Figure`): a pattern that finds its value(s) in README.md, the shell
command that measures it, and a pure function that reads the value(s) from that command's output (and
its wall time). The run prints one table, figure | README says | measured now | command, and flags a
figure whose measured value differs from README's by more than its tolerance (``DIFFERS``); the exit
status is 1 when any does, so a stale figure is found before it is published. CPU figures run with
``--device cpu`` (any machine); figures of a GPU (an H200 in README) run only with ``--device cuda``.
Figures that need hours of training runs or several GPUs are listed as not measured, with what they
need, so the table covers every figure README quotes.

    python -m benchmarks readme-figures --list                          # the figures and their commands
    python -m benchmarks readme-figures --device cpu --out /tmp/rf      # every CPU figure (about 1 h on 2 cores)
    python -m benchmarks readme-figures --device cpu --out /tmp/rf --only import-contracts,body-bmi
    python -m benchmarks readme-figures --device cuda --out /tmp/rf     # the GPU figures on a GPU host

Each command's output goes to ``DIR/NAME.log``; the table to ``DIR/readme_figures.txt`` too.
"""

from __future__ import annotations

import argparse
import json
import re
import shlex
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


WORDS = {"one": 1, "two": 2, "three": 3, "four": 4, "five": 5, "six": 6, "seven": 7, "eight": 8, "nine": 9, "ten": 10}
"""Numbers README writes as words."""


def number(text: str) -> float:
    """A figure as README or a command writes it ("53,520", "0.82", "9", "six") as a float."""
    word = WORDS.get(text.strip().lower())
    return float(word) if word is not None else float(text.replace(",", ""))


@dataclass(frozen=True, kw_only=True)
class Figure:
    """One figure of README.md and how to re-measure it."""

    name: str
    """Its name on the command line (``--only``) and in the table."""
    readme: str
    """A regular expression over README.md (whitespace in it matches any run of whitespace, line breaks
    included); its groups are the figure's values as README quotes them."""
    command: str
    """The shell command that measures it, run from the repository's root; ``{python}``: this
    interpreter, ``{out}``: the ``--out`` folder. Empty: not measured by this runner (``needs`` says why)."""
    parse: Callable[[str, float], tuple[float, ...]] | None = None
    """The measured values from the command's output (stdout and stderr) and its wall time [s], in
    the order of ``readme``'s groups."""
    tolerance: tuple[float, ...] = (0.0,)
    """Per value (the last repeats): the relative difference allowed (0: exactly README's)."""
    device: str = "cpu"
    """``cpu``: measured with ``--device cpu``; ``cuda``: only with ``--device cuda``."""
    minutes: float = 1.0
    """About how long the command takes (2 CPU cores; one H200 for ``cuda``)."""
    needs: str = ""
    """What the command needs beyond this checkout (or, without a command, why it is not measured)."""


def readme_values(text: str, figure: Figure) -> tuple[str, ...] | None:
    """The values ``figure`` quotes in README's ``text`` (strings as written); None when its pattern
    no longer matches (README was reworded: the figure's record must follow)."""
    pattern = re.sub(r"(\\ |\s)+", r"\\s+", figure.readme)
    m = re.search(pattern, text)
    return None if m is None else m.groups()


def compare(said: tuple[str, ...], measured: tuple[float, ...], tolerance: tuple[float, ...]) -> bool:
    """Whether every measured value is within its relative tolerance of README's."""
    if len(said) != len(measured):
        return False
    for k, (s, v) in enumerate(zip(said, measured, strict=True)):
        tol = tolerance[min(k, len(tolerance) - 1)]
        ref = number(s)
        if abs(v - ref) > tol * abs(ref) + 1e-12:
            return False
    return True


def _one(pattern: str, text: str, *, last: bool = False) -> float:
    """The first (or last) match of ``pattern``'s group in ``text``, as a number; ValueError when none."""
    found = re.findall(pattern, text, flags=re.MULTILINE)
    if not found:
        raise ValueError(f"no {pattern!r} in the output")
    return number(found[-1] if last else found[0])


def parse_contracts(out: str, seconds: float) -> tuple[float, ...]:
    """lint-imports: the contracts kept."""
    return (_one(r"Contracts: (\d+) kept", out),)


def parse_bmi(out: str, seconds: float) -> tuple[float, ...]:
    """``drape body info``: the thin, regular and fat presets' BMI."""
    return tuple(_one(rf"preset {name}: .*BMI ([\d.]+)", out) for name in ("thin", "regular", "fat"))


def parse_body_build(out: str, seconds: float) -> tuple[float, ...]:
    """``benchmarks body-build``: drape's part of the body build [s]."""
    return (_one(r"drape's part: ([\d.]+) s", out),)


def parse_labels(out: str, seconds: float) -> tuple[float, ...]:
    """``drape motion list --json``: how many labels."""
    return (float(len(json.loads(out[out.index("{"):]))),)


def parse_generate(out: str, seconds: float) -> tuple[float, ...]:
    """``drape generate``: the scenes that passed (the failure table's ``ok`` row) and all scenes
    (the ``simulated N scenes`` line)."""
    ok = _one(r"^ok\s+0\s+(\d+)", out)
    return ok, _one(r"simulated (\d+) scenes", out)


def parse_tiny(out: str, seconds: float) -> tuple[float, ...]:
    """``drape generate`` of ``tiny``: the scenes simulated and its wall time [min]."""
    return _one(r"simulated (\d+) scenes", out), seconds / 60.0


def parse_paper_motion(out: str, seconds: float) -> tuple[float, ...]:
    """``drape generate --preset paper-motion``: wall minutes and seconds (as README writes them), scenes,
    garment-frames stored, scenes that passed."""
    return (float(seconds // 60), round(seconds % 60, 1), _one(r"simulated (\d+) scenes", out),
            _one(r"(\d+) garment-frames stored", out), _one(r"^ok\s+0\s+(\d+)", out))


def parse_cusick(out: str, seconds: float) -> tuple[float, ...]:
    """``benchmarks cusick``: presets in their range and presets."""
    rows = re.findall(r"^\w+\s+[\d.]+\s+\d+\s+[\d.]+-[\d.]+\s+(True|False)\b", out, flags=re.MULTILINE)
    if not rows:
        raise ValueError("no preset rows in the output")
    return float(rows.count("True")), float(len(rows))


def parse_strips(out: str, seconds: float) -> tuple[float, ...]:
    """The physics tests' preset strips: the largest |error| against the static elongation [%]."""
    errs = re.findall(r"strip at production settings: .*?\(([+-][\d.]+) %\)", out)
    if not errs:
        raise ValueError("no preset strip lines in the output")
    return (max(abs(number(e)) for e in errs),)


def parse_export(out: str, seconds: float) -> tuple[float, ...]:
    """``benchmarks export``: the ``.usd`` file's write time [s] and size [MB]."""
    m = re.search(r"^\S+\.usd\s+([\d.]+)\s+([\d.]+)", out, flags=re.MULTILINE)
    if m is None:
        raise ValueError("no .usd row in the output")
    return number(m.group(1)), number(m.group(2))


def parse_store_size(out: str, seconds: float) -> tuple[float, ...]:
    """``benchmarks store-size``: the total at 4,000 vertices [KiB] (the table's ``total`` row, last column)."""
    return (_one(r"^total\s+\d+\s+(\d+)", out) / 1024.0,)


def parse_patterns(out: str, seconds: float) -> tuple[float, ...]:
    """``benchmarks pattern-survey``: garments that passed the checks, garments, and the median seconds a garment."""
    m = re.search(r"passed the checks (\d+)/(\d+)", out)
    if m is None:
        raise ValueError("no 'passed the checks' line in the output")
    return number(m.group(1)), number(m.group(2)), _one(r"seconds per garment.*?: [\d.e+-]+ / ([\d.e+-]+) /", out)


def parse_six(out: str, seconds: float) -> tuple[float, ...]:
    """``benchmarks sim run-scenes``: runs without a failure."""
    runs = re.findall(r'^\S+/\S+: \{.*"failure": (null|"[^"]*"|\{)', out, flags=re.MULTILINE)
    if not runs:
        raise ValueError("no run lines in the output")
    return (float(runs.count("null")),)


def parse_throughput(out: str, seconds: float) -> tuple[float, ...]:
    """``benchmarks sim run``: garment-frames/s at 256 scenes, self-collision on."""
    return (_one(r"^\s*256\s+on\s+on\s+[\d.]+\s+([\d.]+)", out),)


def parse_newton(out: str, seconds: float) -> tuple[float, ...]:
    """``benchmarks newton``: Newton's ms a frame over drape's at 64 and 256 scenes, self-collision
    on, then off (the speed-ups README quotes)."""
    rows = {}
    for solver, batch, self_, ms in re.findall(r"^\s*(drape|newton\S*)\s+(\d+)\s+(on|off)\s+([\d.]+)", out,
                                               flags=re.MULTILINE):
        rows[("drape" if solver == "drape" else "newton", int(batch), self_)] = number(ms)
    return tuple(rows[("newton", b, s)] / rows[("drape", b, s)] for s in ("on", "off") for b in (64, 256))


FIGURES: tuple[Figure, ...] = (
    # CPU: any machine
    Figure(name="import-contracts", readme=r"the import contracts \((\d+)\) kept in CI", command="lint-imports",
           parse=parse_contracts, minutes=1),
    Figure(name="body-bmi", readme=r"the thin \(BMI ([\d.]+)\), regular \(([\d.]+)\) and fat \(([\d.]+)\) presets",
           command="{python} -m datagen.cli body info", parse=parse_bmi, tolerance=(0.003,), minutes=0.5),
    Figure(name="body-build", readme=r"building drape's body then takes about (\d+) s",
           command="{python} -m benchmarks body-build", parse=parse_body_build, tolerance=(0.5,), minutes=3),
    Figure(name="motion-labels", readme=r"done: (\d+) labels, no interpenetrating frame",
           command="{python} -m datagen.cli motion list --json", parse=parse_labels, minutes=0.2),
    Figure(name="cusick", readme=r"(\d) of (\d) presets in their Cusick ranges",
           command="{python} -m benchmarks cusick", parse=parse_cusick, minutes=8),
    Figure(name="hanging-strips", readme=r"every preset's hanging strip within ([\d.]+) % of its static elongation",
           command="{python} -m pytest -q -s -p no:cacheprovider tests/sim/test_physics.py -k every_preset_hangs",
           parse=parse_strips, tolerance=(0.15,), minutes=8),
    Figure(name="export-usd", readme=r"300 frames of 30,000 vertices: ([\d.]+) s, (\d+) MB as `\.usd`",
           command="{python} -m benchmarks export", parse=parse_export,
           tolerance=(0.5, 0.05), minutes=3),
    Figure(name="tiny-generate", readme=r"the `tiny` dataset preset: (\w+) scenes simulated on the CPU into a validated zarr"
           r" store, `tiny\.zarr`; about (\d+) minutes on 2 cores",
           command="{python} -m datagen.cli generate --out {out}/tiny.zarr --device cpu", parse=parse_tiny,
           tolerance=(0.0, 0.5), minutes=12),
    Figure(name="store-size", readme=r"(\d+) KiB per 4,000-vertex garment-frame",
           command="{python} -m benchmarks store-size {out}/tiny.zarr --vertices 4000", parse=parse_store_size,
           tolerance=(0.05,), minutes=0.5, needs="tiny-generate's store (run it first, same --out)"),
    Figure(name="patterns", readme=r"patterns build, mesh and place: (\d+) of (\d+) \(100 random designs x three bodies\) "
           r"pass the checks, ([\d.]+) s a garment",
           command="{python} -m benchmarks pattern-survey --designs 100", parse=parse_patterns,
           tolerance=(0.0, 0.0, 0.5), minutes=8),
    # GPU: one H200 in README
    Figure(name="small", readme=r"`small` on one H200 \*\*(\d+) of (\d+) pass",
           command="{python} -m datagen.cli generate --preset small --device cuda --out {out}/small.zarr",
           parse=parse_generate, device="cuda", minutes=3),
    Figure(name="paper-motion", readme=r"`paper-motion` in one command on one H200, (\d+) min ([\d.]+) s\*\* "
           r"\((\d+) scenes, ([\d,]+) garment-frames, (\d+) pass\)",
           command="{python} -m datagen.cli generate --preset paper-motion --device cuda --out {out}/pm.zarr",
           parse=parse_paper_motion, tolerance=(0.2, 1.0, 0.0, 0.0, 0.02), device="cuda", minutes=10),
    Figure(name="six-runs", readme=r"6 of 6 presets in their Cusick ranges, the (six) 300-frame runs pass",
           command="{python} -m benchmarks sim prepare-runs --out {out}/runs.pkl --frames 300 && "
                   "{python} -m benchmarks sim run-scenes --inputs {out}/runs.pkl --device cuda",
           parse=parse_six, device="cuda", minutes=6),
    Figure(name="throughput-256", readme=r"([\d.]+) garment-frames/s end to end at 256 scenes",
           command="{python} -m benchmarks sim prepare --out {out}/sim_inputs.npz && "
                   "{python} -m benchmarks sim run --inputs {out}/sim_inputs.npz --device cuda --batches 256 --self on",
           parse=parse_throughput, tolerance=(0.05,), device="cuda", minutes=5),
    Figure(name="newton", readme=r"\*\*([\d.]+)x / ([\d.]+)x with self-collision\*\* at 64 / 256 scenes and "
           r"([\d.]+)x / ([\d.]+)x without",
           command="{python} -m benchmarks sim prepare-runs --out {out}/newton_runs.pkl --garments tshirt --motions walk "
                   "--frames 40 && {python} -m benchmarks newton --inputs {out}/newton_runs.pkl --scene tshirt/walk "
                   "--device cuda --batches 64,256 --self on,off --frames 40 --check-filters --newton-launch graph",
           parse=parse_newton, tolerance=(0.05,), device="cuda", minutes=10,
           needs="newton (pip install -e '.[newton]')"),
    # not measured here: training runs, several GPUs, hours
    Figure(name="garments", readme=r"(ten) types build without penetration or self-intersection \(100 seeds on three bodies",
           command="", needs="`python -m benchmarks garments --seeds 100` (about 3,000 garments: hours on 2 cores); "
                             "its table has no one-line total to read"),
    Figure(name="motions-quality", readme=r"no interpenetrating frame over (\d+) seeds each", command="",
           needs="`python -m benchmarks motions --seeds 50` (hours on 2 cores)"),
    Figure(name="anny-load", readme=r"The first run loads Anny \(about (\d+)-(\d+) minutes on 2 CPU cores", command="",
           needs="a cold Anny cache (~/.cache/anny removed; `python -m benchmarks body-build` prints its load)"),
    Figure(name="pattern-designs", readme=r"([\d,]+) designs counting choices and lengths", command="",
           needs="a count over the programs' choices (docs/patterns.md's table), not a measurement"),
    Figure(name="store-read", readme=r"reads at ([\d.]+)-([\d.]+)x the in-memory rate", command="",
           needs="a read-speed run on a dataset's store (docs/store.md#read-speed)"),
    Figure(name="paper-gnn", readme=r"`paper-gnn` about an (hour) on one GPU", command="",
           needs="an hour of GPU (drape generate --preset paper-gnn --device cuda)"),
    Figure(name="gnn-medium", readme=r"GNN on `medium`: \*\*([\d]+)-([\d]+) % below the skinned garment", command="",
           needs="drape train gnn on the medium store (GPU hours; docs/training.md)"),
    Figure(name="garment-regressor", readme=r"test RMSE ([\d.]+)-([\d.]+) cm against ([\d.]+)-([\d.]+)", command="",
           needs="drape train garment runs (GPU hours; docs/training.md)"),
    Figure(name="motion-generator", readme=r"pose RMSE ([\d.]+) x1e-2", command="",
           needs="drape train motion runs (GPU hours; docs/training.md)"),
    Figure(name="sample-clothed", readme=r"about (\d+) s on an H200 .{0,60} the same command took (\d+) s on 2 CPU cores",
           command="",
           needs="trained motion and garment runs (drape sample clothed)"),
    Figure(name="two-gpus-small", readme=r"2 H200s: ([\d.]+)x on `small`", command="", needs="2 GPUs (--device cuda:0,cuda:1)"),
    Figure(name="paper-motion-4-gpus", readme=r"`paper-motion` on 4 H100s in (\d+) min (\d+) s", command="",
           needs="4 GPUs and Ray (--executor ray)"),
)
"""Every figure README.md quotes, in README's order within each group."""


@dataclass(frozen=True, kw_only=True)
class Row:
    """One line of the table."""

    figure: str
    said: str
    measured: str
    verdict: str
    command: str


def measure(figure: Figure, out: Path, python: str) -> tuple[tuple[float, ...] | None, str]:
    """Run ``figure``'s command (output to ``out/NAME.log``); its values, or None and why not."""
    cmd = figure.command.format(python=shlex.quote(python), out=shlex.quote(str(out)))
    log = out / f"{figure.name}.log"
    t0 = time.perf_counter()
    with open(log, "w") as f:
        f.write(f"$ {cmd}\n")
        f.flush()
        done = subprocess.run(cmd, shell=True, cwd=README.parent, stdout=f, stderr=subprocess.STDOUT, text=True)
    seconds = time.perf_counter() - t0
    text = log.read_text()
    if done.returncode != 0:
        return None, f"exit status {done.returncode} (see {log})"
    try:
        return figure.parse(text, seconds), ""
    except (ValueError, KeyError, json.JSONDecodeError) as e:
        return None, f"unreadable output: {e} (see {log})"


def row(figure: Figure, said: tuple[str, ...] | None, measured: tuple[float, ...] | None, why: str) -> Row:
    """The table's line for one figure."""
    shown = "-" if said is None else " / ".join(said)
    if said is None:
        verdict = "README NO LONGER SAYS IT (update this record)"
    elif measured is None:
        verdict = why
    else:
        verdict = "ok" if compare(said, measured, figure.tolerance) else "DIFFERS"
    value = "-" if measured is None else " / ".join(f"{v:.4g}" for v in measured)
    return Row(figure=figure.name, said=shown, measured=value, verdict=verdict,
               command=figure.command or f"(not run: {figure.needs})")


def format_table(rows: list[Row]) -> str:
    """The table: figure | README says | measured now | verdict | command."""
    head = ("figure", "README says", "measured now", "verdict", "command")
    cells = [head] + [(r.figure, r.said, r.measured, r.verdict, r.command) for r in rows]
    width = [max(len(c[k]) for c in cells) for k in range(4)]
    return "\n".join("  ".join([*(c[k].ljust(width[k]) for k in range(4)), c[4]]) for c in cells)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog="\n\n".join(__doc__.split("\n\n")[1:]))
    ap.add_argument("--device", choices=("cpu", "cuda"), default="cpu",
                    help="which figures to re-measure: the CPU's or the GPU's (README's GPU figures are an H200's)")
    ap.add_argument("--out", type=Path, help="folder for each command's log, its outputs and the table")
    ap.add_argument("--only", default="", help="comma-separated figure names (default: every figure of --device)")
    ap.add_argument("--list", action="store_true", help="print every figure, README's value and its command; run nothing")
    ap.add_argument("--readme", type=Path, default=README, help="the README to check (default: this checkout's)")
    args = ap.parse_args(argv)
    text = args.readme.read_text()
    names = {n for n in args.only.split(",") if n}
    unknown = names - {f.name for f in FIGURES}
    if unknown:
        raise SystemExit(f"no figure {sorted(unknown)}; --list prints them")
    if args.list:
        print(format_table([row(f, readme_values(text, f), None,
                                f"{f.device}, about {f.minutes:g} min" if f.command else "not measured here")
                            for f in FIGURES]))
        return 0
    if args.out is None:
        raise SystemExit("--out DIR is needed to run the commands (their logs and outputs go there)")
    args.out.mkdir(parents=True, exist_ok=True)
    chosen = [f for f in FIGURES if (f.name in names if names else (f.device == args.device or not f.command))]
    rows = []
    for figure in chosen:
        said = readme_values(text, figure)
        if not figure.command or figure.device != args.device:
            why = f"not measured: {figure.needs}" if not figure.command else f"not measured: a {figure.device} figure"
            rows.append(row(figure, said, None, why))
            continue
        print(f"[{time.strftime('%H:%M:%S')}] {figure.name}: about {figure.minutes:g} min ...", flush=True)
        measured, why = measure(figure, args.out, sys.executable)
        rows.append(row(figure, said, measured, why))
        print(f"  {rows[-1].said} -> {rows[-1].measured}: {rows[-1].verdict}", flush=True)
    table = format_table(rows)
    print(table)
    (args.out / "readme_figures.txt").write_text(table + "\n")
    return int(any(r.verdict == "DIFFERS" or r.verdict.startswith("README NO") for r in rows))
