"""Bistability: fold curves in two inputs, cusps and maps of the folds (the paper's scene
with its fast paths, and any scene)."""
