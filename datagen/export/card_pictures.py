"""The pictures beside a store's dataset card (``STORE/card/``): ``preview.png``, a sheet of a few
samples (the last recorded frame of one passed sample per garment family, up to
:data:`SHEET_SAMPLES`, three-quarter view, captioned with the design, material and body), and ``plots/*.png``, the plots of ``drape info --plots``
(:func:`datagen.export.plots.plot_store_info`). ``drape card STORE`` and ``drape generate`` draw
them, then write the card (:func:`datagen.store.card.write_card`), which lists them.
"""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

import numpy as np

from datagen.errors import require

SHEET_SAMPLES = 4
"""Samples on the preview sheet at most."""

TILE = (320, 400)
"""Size of one sample's picture on the sheet (W, H) in pixels (its title says sample, split, garment, body,
motion and frame)."""

CAPTION = 20
"""Pixels under each picture for its caption: the garment design (family:seed), material and body."""


def sheet_samples(store, count: int = SHEET_SAMPLES) -> list[int]:
    """Passed samples with frames to show: one per garment family (in family order), then one per
    (family, split) until ``count``; the first such sample of each."""
    idx = store.index
    T = np.diff(idx["frame_start"])
    ok = np.flatnonzero((idx["failure"] == 0) & (T > 0))
    gtype = store.read("garments/type")
    family = gtype[idx["garment"][ok]]
    chosen: list[int] = []
    for keys in (family, family * 8 + idx["split"][ok]):
        for key in sorted(set(keys.tolist())):
            i = int(ok[keys == key][0])
            if i not in chosen and len(chosen) < count:
                chosen.append(i)
    return sorted(chosen)


def preview_sheet(store, out: Path, *, count: int = SHEET_SAMPLES) -> Path | None:
    """Write the preview sheet of ``store`` (an open reader) to ``out`` (a PNG); None when no sample
    passed (nothing to show)."""
    from PIL import Image, ImageDraw

    from datagen.export.animation import from_store
    from datagen.export.preview import render_frame

    samples = sheet_samples(store, count)
    if not samples:
        return None
    names = store.names
    tiles = []
    with tempfile.TemporaryDirectory(prefix="drape-sheet-") as tmp:
        for i in samples:
            T = store.frame_count(i)
            anim = from_store(store, i, frames=np.array([T - 1]))
            png = render_frame(anim, Path(tmp) / f"{i}.png", frame=0, view="three-quarter", size=TILE)
            s = store.scalars(i)
            g = store.garment(int(s["garment"]))
            caption = (f"{names['garment_type_names'][int(g['type'])]}:{int(g['seed'])}, "
                       f"{names['material_names'][int(g['material'])]}; {names['body_names'][int(s['body'])]}")
            tile = Image.new("RGB", (TILE[0], TILE[1] + CAPTION), "white")
            tile.paste(Image.open(png).convert("RGB"), (0, 0))
            ImageDraw.Draw(tile).text((6, TILE[1] + 4), caption, fill=(20, 20, 20))
            tiles.append(tile)
    sheet = Image.new("RGB", (TILE[0] * len(tiles), TILE[1] + CAPTION), "white")
    for k, tile in enumerate(tiles):
        sheet.paste(tile, (k * TILE[0], 0))
    from datagen.files import atomic_output

    with atomic_output(out) as tmp:
        sheet.save(tmp, format="PNG")
    return out


def draw_card_pictures(path: str | Path) -> list[Path]:
    """Draw ``card/preview.png`` and ``card/plots/*.png`` of the complete store at ``path`` into a
    temporary directory and put it in place of ``card/`` (what was there is replaced once the new
    pictures are drawn). Returns the files."""
    from datagen.export.plots import plot_store_info
    from datagen.store.card import PICTURES_DIR
    from datagen.store.layout import unique_temporary
    from datagen.store.reader import open_store

    require("matplotlib", "drawing a dataset card's pictures", extra="render")
    path = Path(path)
    store = open_store(path, backend="zarr")
    tmp = unique_temporary(path, PICTURES_DIR)  # beside card/, permissions by the umask
    tmp.mkdir()
    try:
        preview_sheet(store, tmp / "preview.png")
        plot_store_info(path, tmp / "plots")
        target = path / PICTURES_DIR
        if target.exists():
            old = path / f".tmp-old-{PICTURES_DIR}-{tmp.name}"
            target.rename(old)
            tmp.rename(target)
            shutil.rmtree(old)
        else:
            tmp.rename(target)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return sorted(target.rglob("*.png"))
