"""Bistability of any scene: fold curves in two inputs, cusps, and maps of the folds."""
