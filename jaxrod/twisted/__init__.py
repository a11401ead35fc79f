"""Rods twisted with both ends held: the framed rod clamped at both ends, its far end turned
and pulled or brought closer (``rod``), its equilibria and branch in the end rotation
(``branch``), their branch points, folds and fold curves."""
