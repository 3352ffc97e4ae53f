"""Shared fixtures: small, seeded data sets for real IPOPT solves."""

import os

import numpy as np
import pytest

os.environ.setdefault("MPLBACKEND", "Agg")

from seds_casadi import Demonstrations  # noqa: E402


def linear_demos(A: np.ndarray, starts: np.ndarray, dt: float = 0.02, steps: int = 60,
                 target=None) -> Demonstrations:
    """Demonstrations integrated exactly from xdot = A (x - x*) (a known stable system)."""
    from scipy.linalg import expm

    target = np.zeros(A.shape[0]) if target is None else np.asarray(target, float)
    E = expm(A * dt)
    pos, vel = [], []
    for x0 in starts:
        xs = [np.asarray(x0, float) - target]
        for _ in range(steps - 1):
            xs.append(E @ xs[-1])
        X = np.array(xs)
        pos.append(X + target)
        vel.append(X @ A.T)
    return Demonstrations(pos, velocities=vel, target=target)


@pytest.fixture(scope="session")
def spiral_demos() -> Demonstrations:
    A = np.array([[-1.0, -2.0], [2.0, -1.0]])
    starts = np.array([[2.0, 0.5], [1.5, 1.8], [-0.3, 2.2]])
    return linear_demos(A, starts, dt=0.05, steps=40)


@pytest.fixture(scope="session")
def curved_demos_3d() -> Demonstrations:
    """Three 3-D demonstrations that curve and end at a target with zero velocity."""
    rng = np.random.default_rng(3)
    t = np.linspace(0, 1, 40)[:, None]
    pos = []
    for _ in range(3):
        start = np.array([-0.5, 0.2, 0.3]) + 0.05 * rng.standard_normal(3)
        bend = np.array([0.0, 0.25, 0.0]) + 0.03 * rng.standard_normal(3)
        s = 3 * t**2 - 2 * t**3  # smooth start and stop
        pos.append(start * (1 - s) + bend * np.sin(np.pi * s) + np.array([0.1, 0.0, 0.05]) * s)
    return Demonstrations(pos, dt=0.025)


# ------------------------------------------------------------------ speed classes
# `pytest -m "not slow"` runs the fast suite (SEDS core, GMM/GMR, motion, ball, learners: under
# two minutes on 2 cores); CI runs everything. Whole modules that drive robots, exudyn, the
# command line or the examples are slow, and so are the single tests listed here (each takes
# several seconds: end-to-end runs, Dask clusters, 50-swing acceptance figures).
SLOW_MODULES = {"test_examples.py", "test_play.py", "test_validation.py",
                "test_robots_control.py", "test_cli_and_lasa.py", "test_readme.py",
                "test_replay.py", "test_validate_workers.py", "test_swing_limits.py"}
SLOW_TESTS = {
    "test_play_checks_its_executor_before_learning",
    "test_workers_stop_within_two_seconds",
    "test_ctrl_c_on_a_command_with_workers_ends_cleanly",
    "test_fifty_random_swings_hit_within_one_degree_and_two_percent",
    "test_a_badly_lined_up_fit_is_refitted_and_reported",
    "test_table1_command_line_quick",
    "test_table1_on_a_dask_local_cluster_gives_the_same_numbers",
    "test_table1_runs_end_to_end_and_is_identical_on_local_processes",
    "test_unreachable_dask_scheduler_is_a_clear_error",
    "test_the_teacher_keeps_to_direct_shots_unless_banks_are_allowed",
    "test_simd_backend_equals_the_casadi_kernel",
    "test_grid_search_picks_seds_components_by_demonstration_folds",
    "test_a_many_component_fit_with_thin_components_is_certified",
    "test_evaluate_shape_dsopt_scores_train_and_test_with_a_certified_model",
    "test_cli_lasa_protocol_ds_opt_writes_the_csv_with_units",
    "test_run_lasa_runs_ds_opt_beside_the_other_protocols",
    "test_hitting_motion_on_a_learned_lyapunov_model",
    "test_seds_learns_and_reproduces_the_7d_joint_space_putts",
    "test_direction_objective_moves_at_the_demonstrated_speeds",
}


def pytest_collection_modifyitems(config, items):
    for item in items:
        name = item.name.split("[")[0]
        if item.path.name in SLOW_MODULES or name in SLOW_TESTS:
            item.add_marker(pytest.mark.slow)
