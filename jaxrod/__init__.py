"""jaxrod: differentiable equilibria and stability of ferromagnetic Kirchhoff rods.

The public API is this one flat namespace (``import jaxrod as jr``); the module tree under it
(``jaxrod.equilibria``, ``jaxrod.solvers``, ...) keeps working for deep imports but is not the
interface. Names are loaded on first use, so ``import jaxrod`` stays cheap (the command line
imports only what a command needs). Importing jaxrod switches JAX to float64.
"""

from __future__ import annotations

import sys

from jaxrod import progress as _progress

# a Ctrl-C while JAX is imported could be swallowed in one of its garbage-collection
# callbacks: it is recorded instead and raised once the import is complete; when the command
# line is starting (``python -m jaxrod.cli``, the ``jaxrod`` command), Ctrl-C stays recorded
# until its command starts, which raises it, to exit with 130 and one line
_command_line = sys.argv[:1] == ["-m"] or sys.argv[0].endswith(("/jaxrod", "\\jaxrod.exe")) \
    or sys.argv[:1] == ["jaxrod"]
with _progress.ctrl_c_guard(defer=True):
    import jax
if _command_line:
    _progress.defer_from_now()
else:
    _progress.raise_pending()

jax.config.update("jax_enable_x64", True)

# imported once the guard above is in place: importlib.metadata alone takes tens of ms
import importlib  # noqa: E402
import importlib.metadata  # noqa: E402

try:
    __version__ = importlib.metadata.version("jaxrod")
except importlib.metadata.PackageNotFoundError:  # a source tree that was not installed
    __version__ = "unknown"

#: The public names, by section of the API reference: public name -> (module, attribute).
#: The documentation's API pages are generated from this table, in this order.
API: dict[str, dict[str, tuple[str, str]]] = {
    "Inputs, units and valid ranges": {
        "Material": ("jaxrod.params", "Material"),
        "Rod": ("jaxrod.params", "Rod"),
        "Magnet": ("jaxrod.params", "Magnet"),
        "preset": ("jaxrod.params", "preset"),
        "gravity_group": ("jaxrod.params", "gravity_group"),
        "anisotropy_group": ("jaxrod.params", "anisotropy_group"),
        "magnet_group": ("jaxrod.params", "magnet_group"),
        "DesignPoint": ("jaxrod.design_point", "DesignPoint"),
        "ValidRange": ("jaxrod.params", "ValidRange"),
        "ParameterError": ("jaxrod.params", "ParameterError"),
    },
    "Scenes (energies)": {
        "UniformField": ("jaxrod.scenes.uniform", "UniformField"),
        "DipoleMagnet": ("jaxrod.scenes.dipole", "DipoleMagnet"),
        "magnet_scene": ("jaxrod.magnet.diagram", "make_scene"),
        "UniformField3D": ("jaxrod.scenes.three_d", "UniformField3D"),
        "DipoleMagnet3D": ("jaxrod.scenes.three_d", "DipoleMagnet3D"),
        "magnet_position": ("jaxrod.scenes.three_d", "magnet_position"),
        "tip_position": ("jaxrod.scenes.dipole", "tip_position"),
        "tip_angle": ("jaxrod.scenes.dipole", "tip_angle"),
    },
    "Any scene: terms, scene files, equilibria, branches, folds, branch points, fold curves, "
    "maps": {
        "Scene": ("jaxrod.scenes.scene", "Scene"),
        "load_scene": ("jaxrod.scenes.files", "load"),
        "term": ("jaxrod.scenes.terms", "term"),
        "Bending": ("jaxrod.scenes.terms", "Bending"),
        "TaperedBending": ("jaxrod.scenes.terms", "TaperedBending"),
        "Gravity": ("jaxrod.scenes.terms", "Gravity"),
        "Anisotropy": ("jaxrod.scenes.terms", "Anisotropy"),
        "Dipole": ("jaxrod.scenes.terms", "Dipole"),
        "Zeeman": ("jaxrod.scenes.terms", "Zeeman"),
        "PointDipole": ("jaxrod.scenes.terms", "PointDipole"),
        "equilibrium": ("jaxrod.equilibria.equilibrium", "equilibrium"),
        "branch": ("jaxrod.equilibria.branch", "branch"),
        "folds": ("jaxrod.magnet.folds", "folds"),
        "fold_function": ("jaxrod.equilibria.folds", "fold_function"),
        "sweep": ("jaxrod.magnet.sweep", "sweep"),
        "branch_points": ("jaxrod.equilibria.branch_points", "branch_points"),
        "bifurcated_branch": ("jaxrod.equilibria.branch_points", "bifurcated_branch"),
        "fold_curve": ("jaxrod.bistability.fold_curve", "fold_curve"),
        "out_of_plane_stability": ("jaxrod.three_d.scene_stability", "out_of_plane_stability"),
        "modes": ("jaxrod.dynamics.modes", "modes"),
        "modes_along": ("jaxrod.dynamics.modes", "modes_along"),
        "in_hertz": ("jaxrod.dynamics.modes", "in_hertz"),
        "simulate": ("jaxrod.dynamics.integrate", "simulate"),
        "snap": ("jaxrod.dynamics.snap", "snap"),
        "fit_folds": ("jaxrod.inverse.scene_fit", "fit_folds"),
        "design_folds": ("jaxrod.inverse.scene_fit", "design_folds"),
        "design_shape": ("jaxrod.inverse.shape_design", "design_shape"),
        "fold_map": ("jaxrod.bistability.fold_map", "fold_map"),
        "read_fold_map": ("jaxrod.bistability.fold_map", "read_fold_map"),
        "Status": ("jaxrod.status", "Status"),
        "SolverError": ("jaxrod.status", "SolverError"),
    },
    "Discretisations": {
        "chebyshev_grid": ("jaxrod.spectral", "chebyshev_grid"),
        "planar_discretisation": ("jaxrod.discretise.planar", "planar_discretisation"),
        "director_discretisation": ("jaxrod.discretise.director", "director_discretisation"),
    },
    "Derivatives": {
        "EnergyModel": ("jaxrod.derivatives", "EnergyModel"),
        "Structured": ("jaxrod.derivatives", "Structured"),
        "Autodiff": ("jaxrod.derivatives", "Autodiff"),
    },
    "Solvers": {
        "newton": ("jaxrod.solvers.newton", "newton"),
        "descend": ("jaxrod.solvers.descent", "descend"),
        "ContinuationOptions": ("jaxrod.solvers.continuation", "ContinuationOptions"),
        "pseudo_arclength": ("jaxrod.solvers.continuation", "pseudo_arclength"),
        "moore_spence_solve": ("jaxrod.solvers.folds", "moore_spence_solve"),
        "differentiable_fold": ("jaxrod.solvers.folds", "differentiable_fold"),
        "least_squares_run": ("jaxrod.solvers.least_squares", "least_squares_run"),
    },
    "Uniform field: the magnetic Greenhill problem": {
        "greenhill": ("jaxrod.uniform.greenhill", "greenhill"),
        "principal_eigenpair": ("jaxrod.uniform.greenhill", "principal_eigenpair"),
        "stability_curve": ("jaxrod.uniform.greenhill", "stability_curve"),
        "greenhill_load": ("jaxrod.uniform.greenhill", "greenhill_load"),
        "critical_length": ("jaxrod.uniform.greenhill", "critical_length"),
        "criticality_switch_load": ("jaxrod.uniform.greenhill", "criticality_switch_load"),
        "buckled_branch": ("jaxrod.uniform.pitchfork", "buckled_branch"),
    },
    "Permanent magnet: branches, folds, hysteresis": {
        "diagram": ("jaxrod.magnet.diagram", "trace_diagram"),
        "fold_pair": ("jaxrod.magnet.folds", "fold_pair"),
        "fold_angles": ("jaxrod.magnet.folds", "fold_angles"),
        "fold_pairs": ("jaxrod.magnet.batch", "fold_pairs"),
        "FoldPairs": ("jaxrod.magnet.batch", "FoldPairs"),
        "square_root_law": ("jaxrod.magnet.sweep", "square_root_law"),
        "conditioning_near_fold": ("jaxrod.magnet.conditioning", "conditioning_near_fold"),
    },
    "The reduced route": {
        "reduction": ("jaxrod.magnet.reduction", "reduction"),
        "reduced_folds": ("jaxrod.magnet.reduction", "reduced_folds"),
        "second_variation_checks": ("jaxrod.magnet.reduction", "second_variation_checks"),
        "certify": ("jaxrod.magnet.contraction", "certify"),
    },
    "Three dimensions": {
        "out_of_plane": ("jaxrod.three_d.outofplane", "out_of_plane"),
        "branch_verdict": ("jaxrod.three_d.outofplane", "branch_verdict"),
        "tilted_track": ("jaxrod.three_d.track", "tilted_track"),
        "track": ("jaxrod.three_d.track", "trace_track"),
    },
    "Twisted rods (both ends held)": {
        "TwistedRod": ("jaxrod.twisted.rod", "TwistedRod"),
        "twist_branch": ("jaxrod.twisted.branch", "twist_branch"),
        "twisted_equilibrium": ("jaxrod.twisted.branch", "twisted_equilibrium"),
        "TwistBranch": ("jaxrod.twisted.branch", "TwistBranch"),
        "TwistState": ("jaxrod.twisted.state", "TwistState"),
        "TwistBranchPoint": ("jaxrod.twisted.branch_points", "TwistBranchPoint"),
        "switch_branch": ("jaxrod.twisted.branch", "switch_branch"),
        "twist_fold_curve": ("jaxrod.twisted.fold_curve", "twist_fold_curve"),
        "TwistFoldCurve": ("jaxrod.twisted.fold_curve", "TwistFoldCurve"),
        "fold_sensitivity": ("jaxrod.twisted.folds", "fold_sensitivity"),
        "fit_twist_folds": ("jaxrod.inverse.twist_fit", "fit_twist_folds"),
        "twist_fold_map": ("jaxrod.twisted.fold_map", "twist_fold_map"),
    },
    "Fold curves, the cusp and design maps": {
        "fold_curves": ("jaxrod.bistability.fold_curves", "fold_curves"),
        "cusp": ("jaxrod.bistability.fold_curves", "find_cusp"),
        "cusp_location": ("jaxrod.bistability.fold_curves", "cusp_location"),
        "MapAxis": ("jaxrod.bistability.design_map", "MapAxis"),
        "MapSpec": ("jaxrod.bistability.design_map", "MapSpec"),
        "bistability_map": ("jaxrod.bistability.design_map", "run_map"),
        "read_map": ("jaxrod.bistability.design_map", "read_store"),
        "cusp_curve": ("jaxrod.bistability.design_map", "cusp_curve"),
        "fold_crossings": ("jaxrod.bistability.design_map", "fold_crossings"),
    },
    "Calibration and inverse design": {
        "fit": ("jaxrod.inverse.fit", "fit"),
        "Prior": ("jaxrod.inverse.fit", "Prior"),
        "profile": ("jaxrod.inverse.fit", "profile"),
        "default_point": ("jaxrod.inverse.fit", "default_point"),
        "fit_youngs_modulus": ("jaxrod.inverse.youngs", "fit_youngs_modulus"),
        "fit_batch": ("jaxrod.inverse.youngs", "fit_batch"),
        "FitSetup": ("jaxrod.inverse.youngs", "FitSetup"),
        "design": ("jaxrod.inverse.design", "design"),
    },
    "Figures": {
        "stability_diagram_figure": ("jaxrod.plotting", "stability_diagram_figure"),
        "diagram_figure": ("jaxrod.plotting", "diagram_figure"),
        "hysteresis_figure": ("jaxrod.plotting", "hysteresis_figure"),
        "conditioning_figure": ("jaxrod.plotting", "conditioning_figure"),
        "fold_curve_figure": ("jaxrod.plotting", "fold_curve_figure"),
        "design_map_figure": ("jaxrod.plotting", "design_map_figure"),
        "profile_figure": ("jaxrod.plotting", "profile_figure"),
    },
    "Long runs": {
        "Interrupted": ("jaxrod.progress", "Interrupted"),
        "enable_caches": ("jaxrod.stored", "enable_caches"),
        "enable_store": ("jaxrod.stored", "enable_store"),
    },
}

_WHERE = {name: where for section in API.values() for name, where in section.items()}

__all__ = list(_WHERE)


def __getattr__(name: str):
    """Load a public name on first use (PEP 562) and keep it."""
    if name not in _WHERE:
        raise AttributeError(f"module 'jaxrod' has no attribute {name!r}")
    module, attribute = _WHERE[name]
    value = getattr(importlib.import_module(module), attribute)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
