import atexit
import os
import shutil
import sys
import tempfile

import pytest

sys.path.insert(0, os.path.dirname(__file__))
# One fresh cache folder for this test session, shared by the test workers and every process
# they start (benchmark scripts, notebooks, the CLI): JAX's compilation cache, so that a
# program that several of them compile is compiled once, and the command line's store of
# traced programs (``jaxrod.stored``; the CLI keeps its caches on, as it does for users), so
# that a command run in several processes (a map interrupted and resumed, say) is traced once.
# Tests never read or write a user's cache. Created by the first process (the xdist
# controller), removed when it exits; the benchmark that measures compile times gives its
# children no cache of ours.
if "JAXROD_TEST_CACHE" not in os.environ:
    _cache = tempfile.mkdtemp(prefix="jaxrod-test-cache-")
    atexit.register(shutil.rmtree, _cache, ignore_errors=True)
    os.environ["JAXROD_TEST_CACHE"] = _cache
    os.environ["JAXROD_CACHE_DIR"] = _cache
    os.environ.setdefault("JAX_COMPILATION_CACHE_DIR", _cache)
    os.environ.setdefault("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", "0.2")

#: XLA's option for the tests' programs: LLVM's lowest optimisation level. Most of the suite's
#: time is XLA compiling programs that then run for milliseconds; at this level the same
#: programs compile about a quarter faster and do the same arithmetic (IEEE, no fast-math at
#: either level): the same numbers to round-off, more slowly. The benchmarks' quick forms run
#: without it, as users' programs do (``tests/test_benchmarks.py``).
TEST_XLA_FLAG = "--xla_backend_optimization_level=0"
if TEST_XLA_FLAG not in os.environ.get("XLA_FLAGS", ""):
    os.environ["XLA_FLAGS"] = f"{os.environ.get('XLA_FLAGS', '')} {TEST_XLA_FLAG}".strip()

import jaxrod  # noqa: E402,F401  (sets float64)
import jaxrod.cli  # noqa: E402

# Command lines run in a test's own process (tests/command_line.py) share the programs that
# the worker has compiled: they leave the store of exported programs off (JAX's persistent
# cache is on from the environment above). The processes that tests start keep the store.
jaxrod.cli._enable_compilation_cache = lambda: None

#: Modules whose tests each run in their own subprocess: spread over the xdist workers one
#: test at a time. Every other module stays on one worker, so that its module-scoped fixtures
#: and compiled programs are built once.
SPREAD = {"test_benchmarks.py", "test_notebooks.py"}
#: Modules of the slow tier as a whole (``python -m pytest -m slow``): the benchmarks' quick
#: forms and the notebooks, each a process of its own.
SLOW = SPREAD
#: Tests of the slow tier: derivatives against finite differences or whole-energy autodiff
#: beside the assembled ones the default tier checks (``test_engine``), spectral convergence
#: sweeps and the same check at other N, stress and interruption runs, the main job, the
#: long command-line runs whose analyses the default tier checks in Python, and second cases
#: of a behaviour the default tier checks once (a design in groups, eight devices beside
#: four, other integrators' Kelvin-Voigt damping). CI runs them after the default tier.
SLOW_TESTS = {
    "test_derivatives.py::test_assembled_derivatives_match_autodiff",
    "test_engine.py::test_the_papers_scenes_are_their_printed_energies",
    "test_engine.py::test_the_generic_fold_curve_of_the_papers_scene_passes_its_cusp",
    "test_new_terms.py::test_assembled_derivatives_equal_autodiff",
    "test_new_terms.py::test_a_programmed_magnetisation_in_a_magnets_field",
    "test_calibration.py::test_chain_rule_jacobian_matches_central_differences",
    "test_fold_curves.py::test_cusp_location_derivatives_match_finite_differences",
    "test_fold_curves.py::test_cusp_agrees_with_merging_fold_pairs",
    "test_reduction.py::test_implicit_derivatives_of_w_match_finite_differences",
    "test_reduction.py::test_reduced_function_is_the_q_derivative_of_the_reduced_energy_and_"
    "vanishes_on_branch",
    "test_reduction.py::test_second_variation_decomposition_at_and_near_the_folds",
    "test_fit.py::test_fold_angle_gradients_match_central_differences",
    "test_magnet.py::test_spectral_convergence_of_fold_angle",
    "test_scene_files.py::test_spectral_convergence_of_the_tip_angle",
    "test_batch.py::test_near_the_cusp_every_answer_is_that_of_locate_folds",
    "test_batch.py::test_no_bistable_set_is_reported_without_its_folds",
    "test_batch.py::test_two_programs_at_once_do_not_hang",
    "test_batch.py::test_tier_one_alone_reports_not_converged_never_not_bistable",
    "test_batch.py::test_small_clearances_found_from_the_first_bracketing_cells",
    "test_soak.py::test_thousands_of_mixed_calls_keep_mappings_and_memory_flat",
    "test_design_map.py::test_ctrl_c_at_ten_moments_exits_130_and_keeps_the_finished_chunks",
    "test_cli.py::test_reproduce_writes_report",
    "test_cli.py::test_track_json_and_files",
    "test_figures.py::test_design_map_figure",
    "test_outofplane.py::test_out_of_plane_form_is_positive_on_the_engaged_branch_and_"
    "matches_the_formula",
    "test_scene_stability.py::test_the_papers_scene_as_terms_against_the_papers_check",
    "test_dynamics.py::test_cli_snap_json",
    "test_dynamics.py::test_cli_snap_of_the_papers_wire_in_seconds",
    "test_dynamics.py::test_the_snap_duration_is_differentiable_in_youngs_modulus",
    "test_dynamics.py::test_the_discrete_gradient_conserves_the_energy_of_a_large_motion",
    "test_dynamics.py::test_the_3d_rod_swings_as_the_planar_one",
    "test_scene_files.py::test_cli_sweep_of_a_scene_file_snaps_past_the_fold",
    "test_scene_files.py::test_cli_map_on_a_scene_file",
    "test_engine.py::test_assembled_derivatives_equal_autodiff_of_the_whole_energy[3d]",
    "test_three_d.py::test_magnet_track_leaving_the_plane_snaps_where_the_planar_folds_are",
    "test_figures.py::test_fold_curve_figure",
    "test_calibration.py::test_fold_derivatives_match_central_differences_of_fresh_continuations",
    "test_calibration.py::test_design_with_groups",
    "test_bad_inputs.py::test_sigint_keeps_the_partial_sweep",
    "test_engine.py::test_two_folds_within_one_step_near_the_cusp_are_found[0.0001-16]",
    "test_branch_points.py::test_the_opposed_field_buckles_the_cantilever_at_pi_squared_over_four"
    "[8]",
    "test_branch_points.py::test_the_opposed_field_buckles_the_cantilever_at_pi_squared_over_four"
    "[12]",
    "test_branch_points.py::test_the_opposed_field_buckles_the_cantilever_at_pi_squared_over_four"
    "[24]",
    "test_dynamics.py::test_kelvin_voigt_damps_a_mode_as_its_frequency_squared[midpoint]",
    "test_dynamics.py::test_kelvin_voigt_damps_a_mode_as_its_frequency_squared[bdf2]",
    "test_design_map.py::test_eight_devices_identical_to_one",
    "test_figures.py::test_fold_curve_figure_shades_only_the_sweeps_bistability",
}


def pytest_collection_modifyitems(config, items):
    for item in items:
        name = os.path.basename(str(item.fspath))
        if name in SLOW or f"{name}::{item.originalname}" in SLOW_TESTS \
                or f"{name}::{item.name}" in SLOW_TESTS:
            item.add_marker(pytest.mark.slow)
        if name not in SPREAD:
            item.add_marker(pytest.mark.xdist_group(name))
    # the long subprocess tests first, so that no worker is left with one at the end
    items.sort(key=lambda item: os.path.basename(str(item.fspath)) not in SPREAD)


#: Memory mappings above which a test process drops its compiled programs between modules.
#: XLA's CPU backend maps every executable's code and data; a worker that compiles many
#: distinct programs (each module its own scenes, degrees and shapes) approaches the kernel's
#: limit (vm.max_map_count, 65530 by default) and then aborts inside a compilation. The
#: mappings of repeated calls stay flat (tests/test_soak.py); this is only about how many
#: different programs one process holds.
MAPPINGS_HIGH = 25_000


def _mappings() -> int:
    try:
        with open("/proc/self/maps") as f:
            return sum(1 for _ in f)
    except OSError:  # not Linux: no such limit to watch
        return 0


@pytest.fixture(scope="module", autouse=True)
def _release_programs_when_mappings_are_high():
    yield
    if _mappings() > MAPPINGS_HIGH:
        import gc

        import jax

        jax.clear_caches()
        gc.collect()

