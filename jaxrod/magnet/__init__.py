"""The permanent magnet on its circle (the paper's rig): the diagram, folds, fold pairs
for many designs (the fast path), the hysteresis sweep, and the reduced route."""
