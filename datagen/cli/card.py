"""``drape card STORE``: write (again) the dataset card of a store, its per-sample table, its
Croissant description and its pictures (:mod:`datagen.store.card`, :mod:`datagen.export.card_pictures`)."""

from __future__ import annotations

from pathlib import Path

from datagen.errors import InputError


def register(sub, formatter) -> None:
    p = sub.add_parser("card", formatter_class=formatter, help="write a store's dataset card (README.md) and table",
                       description="Write the dataset card of a complete store: README.md at its root (Hugging Face "
                       "dataset-card metadata; what it holds, how it was made, licences, statistics, the schema of "
                       "every array, pictures, how to load it), the per-sample table table/{split}.parquet, "
                       "croissant.json, and the pictures under card/ (a preview sheet and the plots of drape info "
                       "--plots). Every fact comes from the store; drape validate checks the card against it. A store "
                       "that is not complete or is damaged gets no card (exit 1).",
                       epilog="examples:\n  drape card tiny.zarr\n  drape card tiny.zarr --no-pictures")
    p.add_argument("store")
    p.add_argument("--no-pictures", action="store_true",
                   help="keep the pictures already under card/ (or none) instead of drawing them")
    p.set_defaults(func=_cmd_card)


def write_card_with_pictures(store: Path, *, pictures: bool = True, check_files: bool = True) -> list[Path]:
    """Check the store (nothing written if it is damaged or unfinished), draw its pictures, write its card."""
    from datagen.store.card import open_checked, write_card

    open_checked(store, check_files=check_files)
    drawn = []
    if pictures:
        from datagen.export.card_pictures import draw_card_pictures

        drawn = draw_card_pictures(store)
    return drawn + write_card(store, check_files=False)


def _cmd_card(args) -> int:
    store = Path(args.store)
    if not store.is_dir():
        raise InputError(f"{store} is not a directory; give a store made by drape generate")
    written = write_card_with_pictures(store, pictures=not args.no_pictures)
    card = next(p for p in written if p.name == "README.md")
    print(f"wrote {card} and {len(written) - 1} files beside it: "
          + ", ".join(sorted({str(p.relative_to(store).parts[0]) for p in written if p != card})))
    return 0
