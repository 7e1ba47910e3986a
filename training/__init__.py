"""drape's torch side: datasets over the store, the papers' models, losses and trainers.

The trainers read the zarr store that ``datagen.store`` writes; they arrive with the store.
"""
