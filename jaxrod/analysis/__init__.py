"""Deprecated: the analyses moved to folders named by the question they answer (see
docs/layout.md): ``jaxrod.uniform`` (the Greenhill problem), ``jaxrod.magnet`` (the
permanent magnet: diagram, folds, fold pairs, the reduced route), ``jaxrod.three_d``,
``jaxrod.bistability`` (fold curves, cusps, maps), ``jaxrod.inverse`` (fit, design) and
``jaxrod.equilibria`` (any scene). Each old module path still imports, as an alias of its new
module, with a DeprecationWarning; the aliases go in the next release."""

from __future__ import annotations

import importlib
import sys
import warnings

#: old module -> new module
MOVED = {
    "greenhill": "uniform.greenhill",
    "pitchfork": "uniform.pitchfork",
    "magnet_track": "three_d.track",
    "magnet": "magnet.diagram + magnet.folds + magnet.sweep",
    "batch": "magnet.batch",
    "reduction": "magnet.reduction",
    "contraction": "magnet.contraction",
    "conditioning": "magnet.conditioning",
    "outofplane": "three_d.outofplane",
    "fold_curves": "bistability.fold_curves",
    "design_map": "bistability.design_map",
    "calibration": "inverse.calibration",
    "fit": "inverse.fit + inverse.youngs",
    "design": "inverse.design",
    "branch": "equilibria.record",
}


def alias(old: str) -> None:
    """Make ``jaxrod.analysis.<old>`` the new module itself (the same object: its private
    names and monkeypatching work through either path), with a DeprecationWarning."""
    new = "jaxrod." + MOVED[old]
    warnings.warn(f"jaxrod.analysis.{old} moved to {new}; the old path goes in the next "
                  "release", DeprecationWarning, stacklevel=3)
    sys.modules[f"jaxrod.analysis.{old}"] = importlib.import_module(new)


def merged(old: str, namespace: dict) -> None:
    """Fill ``namespace`` (the old module's globals) with every name of the modules it was
    split into, with a DeprecationWarning."""
    parts = MOVED[old].split(" + ")
    warnings.warn(f"jaxrod.analysis.{old} was split into "
                  f"{', '.join('jaxrod.' + p for p in parts)}; the old path goes in the next "
                  "release", DeprecationWarning, stacklevel=3)
    for part in parts:
        module = importlib.import_module("jaxrod." + part)
        namespace.update({k: v for k, v in vars(module).items() if not k.startswith("__")})
