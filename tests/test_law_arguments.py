"""The adaptive and robust laws (navcore.filters.adaptive_laws, robust_laws) refuse an argument
of the wrong shape or with a NaN by an error whose message starts with that argument's name
(the contract of navcore.filters.array_checks), and their parameters at the edges of the
documented ranges; a few values worked out by hand.
"""
from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from navcore.errors import InputError, ParameterError
from navcore.filters import adaptive_laws as al
from navcore.filters import robust_laws as rl
from lapack_cases import case_where_the_solves_differ

M, N = 2, 3                                   # measurement and state dimensions
H = np.hstack([np.eye(M), np.zeros((M, 1))])  # (2, 3)
GOOD = {
    al.sage_husa_r_update: dict(R_prev=np.eye(M), innovation=[0.1, -0.2], H=H, K=0.5 * H.T,
                                P_post=0.1 * np.eye(N), k=3, b=0.9),
    al.divergence_test: dict(innovation=[0.1, -0.2], HPH_prior=np.eye(M), R=np.eye(M)),
    al.fading_factor: dict(innovation=[0.1, -0.2], HQH=np.eye(M), R=np.eye(M),
                           HPpredH_no_Q=np.eye(M)),
    al.fading_predict: dict(P_propagated=np.eye(N), GQG=np.eye(N), lam=2.0),
    al.compression_factor: dict(innovation=[0.1, -0.2], G=np.eye(M), K=0.5 * H.T),
    al.guard_positive_definite: dict(R=np.eye(M), R_min=0.5),
    rl.chi_square_faults: dict(innovation=[0.1, -0.2], S=np.eye(M)),
}


def _spoiled(value, how):
    a = np.array(value, dtype=float)
    if how == "nan":
        a.flat[0] = math.nan
        return a
    if how == "one more row":
        return np.vstack([a, a[:1]])
    if how == "one more column":
        return np.hstack([a, a[:, :1]])
    return np.pad(a, ((0, 1), (0, 1)))          # "one larger": square, of the wrong size


# (law, argument, spoil): the first array argument of each law sets the dimension, so only
# its NaN is its own error
SPOILS = [
    (al.sage_husa_r_update, "innovation", "nan"), (al.sage_husa_r_update, "R_prev", "nan"),
    (al.sage_husa_r_update, "R_prev", "one larger"), (al.sage_husa_r_update, "H", "nan"),
    (al.sage_husa_r_update, "H", "one more row"), (al.sage_husa_r_update, "K", "nan"),
    (al.sage_husa_r_update, "K", "one more row"), (al.sage_husa_r_update, "K", "one more column"),
    (al.sage_husa_r_update, "P_post", "nan"), (al.sage_husa_r_update, "P_post", "one larger"),
    (al.divergence_test, "innovation", "nan"), (al.divergence_test, "HPH_prior", "nan"),
    (al.divergence_test, "HPH_prior", "one larger"), (al.divergence_test, "R", "nan"),
    (al.divergence_test, "R", "one larger"),
    (al.fading_factor, "innovation", "nan"), (al.fading_factor, "HQH", "nan"),
    (al.fading_factor, "HQH", "one larger"), (al.fading_factor, "R", "nan"),
    (al.fading_factor, "R", "one larger"), (al.fading_factor, "HPpredH_no_Q", "nan"),
    (al.fading_factor, "HPpredH_no_Q", "one larger"),
    (al.fading_predict, "P_propagated", "nan"), (al.fading_predict, "P_propagated", "one more row"),
    (al.fading_predict, "GQG", "nan"), (al.fading_predict, "GQG", "one larger"),
    (al.compression_factor, "innovation", "nan"), (al.compression_factor, "G", "nan"),
    (al.compression_factor, "G", "one larger"), (al.compression_factor, "K", "nan"),
    (al.compression_factor, "K", "one more column"),
    (al.guard_positive_definite, "R", "nan"), (al.guard_positive_definite, "R", "one more row"),
    (al.guard_positive_definite, "R_min", "nan"),
]


@pytest.mark.parametrize("law, name, how", SPOILS,
                         ids=[f"{law.__name__}-{name}-{how}" for law, name, how in SPOILS])
def test_a_spoiled_argument_is_named(law, name, how):
    args = dict(GOOD[law])
    args[name] = _spoiled(args[name], how)
    with pytest.raises((InputError, ParameterError), match=rf"^{name}: "):
        law(**args)


@pytest.mark.parametrize("law", sorted(GOOD, key=lambda f: f.__name__), ids=lambda f: f.__name__)
def test_the_unspoiled_arguments_are_accepted(law):
    law(**GOOD[law])


def test_parameters_at_the_edges_of_their_ranges():
    with pytest.raises(ParameterError, match=r"^b \(Sage-Husa"):
        al.sage_husa_weight(3, 0.0)
    for fraction in (0.0, -1.0, math.inf):
        with pytest.raises(ParameterError, match=r"^fraction "):
            al.r_floor_from_initial(np.eye(2), fraction)
    for R0 in ([1.0, 0.0], [1.0, -1.0], [1.0, math.nan]):
        with pytest.raises(ParameterError, match=r"^R0: "):
            al.r_floor_from_initial(R0)
    with pytest.raises(ParameterError, match=r"^R0: "):
        al.r_floor_from_initial(np.diag([1.0, 0.0]))
    for cap in (0.5, math.inf):
        with pytest.raises(ParameterError, match=r"^max_factor "):
            al.fading_factor(**GOOD[al.fading_factor], max_factor=cap)
    for D in (0.0, -1.0, math.inf):
        with pytest.raises(ParameterError, match=r"^D "):
            al.compression_factor(**GOOD[al.compression_factor], D=D)


def test_r_floor_of_a_diagonal_given_as_a_vector():
    assert al.r_floor_from_initial([4.0, 9.0]).tolist() == pytest.approx([0.04, 0.09])
    assert al.r_floor_from_initial(np.diag([4.0, 9.0]), 0.5).tolist() == [2.0, 4.5]


def test_guard_floors_the_scaled_eigenvalues_at_one():
    # S = D^-1 R D^-1 = diag(0.5, 4) with D = 1: floored to diag(1, 4)
    out = al.guard_positive_definite(np.diag([0.5, 4.0]), [1.0, 1.0])
    assert out == pytest.approx(np.diag([1.0, 4.0]))
    # R_min = (4, 1): S = diag(0.125, 4) -> diag(1, 4) -> R = diag(4, 4)
    assert al.guard_positive_definite(np.diag([0.5, 4.0]), [4.0, 1.0]) == pytest.approx(
        np.diag([4.0, 4.0]))


def test_a_healthy_r_passes_the_guard_bit_for_bit():
    # the fast path: R - diag(R_min) positive definite, R returned as it is (no eigen round trip)
    R = np.array([[2.0, 0.3], [0.3, 1.7]]) / 3.0
    assert np.array_equal(al.guard_positive_definite(R, [0.1, 0.1]), R)


def test_max_factor_one_is_allowed_and_caps():
    # v'v = 20, traces: HQH 2, R 2, HPH0 2: lambda = (20 - 4) / 2 = 8, capped at 1 and at 2
    args = dict(GOOD[al.fading_factor], innovation=[4.0, 2.0])
    assert al.fading_factor(**args) == pytest.approx(8.0)
    assert al.fading_factor(**args, max_factor=1.0) == 1.0
    assert al.fading_factor(**args, max_factor=2.0) == 2.0


def test_fading_factor_tests_divergence_on_the_predicted_covariance():
    # eq. 11 with H P_{k,k-1} H' = HPH0 + HQH: tr = 2 + 2 + 2 = 6 >= v'v = 5 passes (lambda 1);
    # with HPH0 - HQH the trace would be 2 and the test fail
    args = dict(GOOD[al.fading_factor], innovation=[2.0, 1.0])
    assert al.fading_factor(**args) == 1.0


def test_fading_factor_with_a_small_positive_denominator():
    # tr(HPH0) = 0.5 (below 1 but > 0): lambda = (v'v - tr HQH - tr R) / 0.5 = (20 - 4) / 0.5
    args = dict(GOOD[al.fading_factor], innovation=[4.0, 2.0], HPpredH_no_Q=0.25 * np.eye(M))
    assert al.fading_factor(**args) == pytest.approx(32.0)


def test_divergence_test_holds_at_equality():
    # v'v = 4 = gamma (tr HPH + tr R) = 1 * (2 + 2)
    assert al.divergence_test([2.0, 0.0], np.eye(M), np.eye(M))


def test_compression_with_d_below_one():
    # K G K' = 0.25 I (lambda 0.25); D = 0.5: gate D^2 / lambda = 1; tau = 4 -> Y = D/sqrt(tau lam)
    Y, tau, gate = al.compression_factor([2.0, 0.0], np.eye(M), 0.5 * H.T, D=0.5)
    assert (tau, gate) == pytest.approx((4.0, 1.0))
    assert Y == pytest.approx(0.5 / math.sqrt(4.0 * 0.25))
    # at the gate: Y = 1 exactly
    assert al.compression_factor([1.0, 0.0], np.eye(M), 0.5 * H.T, D=0.5)[0] == 1.0


def test_compression_with_a_small_gain():
    # K = 0.1 H': lambda = 0.01 (below 1, not zero): gate 1 / 0.01 = 100
    Y, tau, gate = al.compression_factor([2.0, 0.0], np.eye(M), 0.1 * H.T, D=1.0)
    assert gate == pytest.approx(100.0) and Y == 1.0


def test_compression_nis_is_numpys_lu_solve_of_numpys_factor():
    """The documented arithmetic of the compression factor (paper 001's), bit for bit: tau =
    |u|^2 with u from numpy's solve with numpy's Cholesky factor, not a triangular solve."""
    S, v, _, nis_lu = case_where_the_solves_differ()
    tau = al.compression_factor(v, S, np.eye(3))[1]
    assert tau == nis_lu


# -- robust laws ----------------------------------------------------------------------------
def test_chi_square_threshold_range_and_strict_comparison():
    for threshold in (0.0, -1.0, math.inf):
        with pytest.raises(ParameterError, match=r"^threshold "):
            rl.chi_square_faults([2.0, 0.0], np.eye(M), threshold)
    # r = (4, 0): a component exactly at the threshold is not a fault
    assert rl.chi_square_faults([2.0, 0.0], np.eye(M), 4.0).tolist() == [False, False]
    assert rl.chi_square_faults([2.0, 0.0], np.eye(M), 0.5).tolist() == [True, False]


def test_newton_order_range_and_default():
    for order in (-1, 2.5):
        with pytest.raises(ParameterError, match=r"^order "):
            rl.newton_forward_extrapolate([1.0, 2.0], order)
    # default order 4: exact for t^4 (0, 1, 16, 81, 256 -> 625); order 3 would give 601
    assert rl.newton_forward_extrapolate([0.0, 1.0, 16.0, 81.0, 256.0]) == pytest.approx(625.0)


def test_observation_history_length_and_defaults():
    for maxlen in (0, 1.5):
        with pytest.raises(ParameterError, match=r"^maxlen "):
            rl.ObservationHistory(maxlen)
    one = rl.ObservationHistory(1)
    one.append([1.0])
    one.append([2.0])
    assert one.samples().tolist() == [[2.0]]
    history = rl.ObservationHistory()          # maxlen 5
    assert history.samples().shape == (0, 0)
    for k in range(7):
        history.append([float(k * k)])
    assert len(history) == 5 and history.last_epoch == 6
    # default order 4 on 2..6 squared: exact for a quadratic, 49
    assert history.predict_next() == pytest.approx([49.0])
    assert history.predict_next(order=1) == pytest.approx([36.0 + 11.0])


def test_observation_history_epochs_start_at_zero_and_clear():
    history = rl.ObservationHistory(3)
    history.append([1.0])
    assert history.last_epoch == 0
    history.clear()
    assert len(history) == 0 and history.last_epoch is None
    history.append([1.0])
    assert history.last_epoch == 0
    with pytest.raises(InputError, match=r"^ObservationHistory: no previous"):
        rl.ObservationHistory(3).predict_next()


def test_observation_history_argument_names():
    history = rl.ObservationHistory(3)
    with pytest.raises(InputError, match=r"^z: contains NaN"):
        history.append([math.nan])
    history.append([1.0, 2.0])
    with pytest.raises(InputError, match=r"^delta_z: contains NaN"):
        history.apply_correction([math.nan, 0.0])
    with pytest.raises(InputError, match=r"^delta_z: shape"):
        history.apply_correction([1.0])
    history.apply_correction([0.5, 0.5])       # one stored sample, of the same shape
    assert history.samples().tolist() == [[0.5, 1.5]]


def test_igg3_constants_and_default_weight():
    for k0, k1 in ((0.0, 3.0), (-1.0, 3.0), (2.0, 2.0), (3.0, 2.0), (1.5, math.inf)):
        with pytest.raises(ParameterError, match=r"^k0, k1 "):
            rl.igg3_weight(2.0, k0, k1)
    # defaults k0 = 1.5, k1 = 3: w(2) = (1.5 / 2) ((3 - 2) / 1.5)^2 = 1/3, a Python float
    w = rl.igg3_weight(2.0)
    assert isinstance(w, float) and w == pytest.approx(1.0 / 3.0)


def test_igg3_of_a_zero_residual_warns_nothing():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert rl.igg3_weight(np.array([0.0, 2.0])).tolist() == pytest.approx([1.0, 1.0 / 3.0])


def test_r_floor_of_a_scalar_r0_is_one_floor():
    assert al.r_floor_from_initial(4.0).tolist() == pytest.approx([0.04])


def test_the_reserve_coefficient_defaults_to_one():
    # v'v = 10 against tr(HPH) + tr(R) = 4 (gamma 1) or 8 (gamma 2): fails either way;
    # v'v = 5 passes only with gamma >= 1.25
    assert not al.divergence_test([3.0, 1.0], np.eye(M), np.eye(M))
    assert not al.divergence_test([2.0, 1.0], np.eye(M), np.eye(M))
    assert al.divergence_test([2.0, 1.0], np.eye(M), np.eye(M), gamma=1.25)
    # fading factor with traces 2, 2, 2: v'v = 10 fails the test at gamma 1: (10 - 4) / 2
    assert al.fading_factor([3.0, 1.0], np.eye(M), np.eye(M), np.eye(M)) == pytest.approx(3.0)


def test_fading_factor_with_a_reserve_coefficient_of_two():
    # eq. 11 at gamma 2: v'v = 10 <= 2 tr(HPH0 + HQH + R) = 12 passes: lambda 1
    assert al.fading_factor([3.0, 1.0], np.eye(M), np.eye(M), np.eye(M), gamma=2.0) == 1.0


def test_compression_names_g_when_it_is_not_positive_definite():
    with pytest.raises(InputError, match=r"^G: innovation covariance 'S' is not positive"):
        al.compression_factor([1.0, 0.0], -np.eye(M), 0.5 * H.T)


def test_newton_default_order_is_four_also_with_more_samples():
    # t^5 at t = 0..5: order 4 misses 6^5 = 7776 by the fifth difference 5! = 120
    samples = [float(t ** 5) for t in range(6)]
    assert rl.newton_forward_extrapolate(samples) == pytest.approx(7776.0 - 120.0)
    history = rl.ObservationHistory(6)
    for value in samples:
        history.append([value])
    assert history.predict_next() == pytest.approx([7776.0 - 120.0])
