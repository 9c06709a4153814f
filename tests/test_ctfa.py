"""Component verification of the CTFA process-noise schedule (paper 000 eqs. 24-25)."""
import copy

import numpy as np
import pytest

from navcore.core.component import InputError, ParameterError
from navcore.filters.ctfa import PAPER_T1, PAPER_T2, CtfaQSchedule, ctfa_q_scale, ctfa_thresholds
from navcore.filters.innovation_stats import chi_square_statistic
from navcore.filters.unscented import UnscentedKalmanFilter

QMIN = np.diag([1e-6, 2e-6, 3e-6])
QMAX = 10.0 * QMIN          # the paper takes Q_max as an integer multiple of Q_min


def paper_eq25(q, Qmin, Qmax, Q_previous):
    """Eq. 25 transcribed literally, with the paper's numbers."""
    if q < 6.25:
        return Q_previous
    if q <= 11.35:
        return 1.0 / 5.1 * (q - 6.25) * (Qmax - Qmin) + Qmin
    return Qmax


def scheduled_q(q, previous_weight=0.0):
    """Q of the schedule the filter runs for statistic ``q``, from the weight
    ``previous_weight`` of Q_{k-1} (0: Q_0 = Q_min)."""
    schedule = CtfaQSchedule(QMIN, QMAX)
    schedule.weight = previous_weight
    schedule.Q = QMIN + previous_weight * (QMAX - QMIN)
    return schedule.update(q)


def test_thresholds_for_three_dof_match_the_paper():
    T1, T2 = ctfa_thresholds(3)
    assert round(T1, 3) == 6.251 and round(T2, 3) == 11.345
    # the paper prints 6.25 and 11.35 (11.345 rounded up)
    assert round(T1, 2) == PAPER_T1 and abs(T2 - PAPER_T2) < 0.006
    assert PAPER_T2 - PAPER_T1 == pytest.approx(5.1)       # the 1/5.1 slope of eq. 25


def test_thresholds_grow_with_dof_and_reject_bad_arguments():
    pairs = [ctfa_thresholds(d) for d in range(1, 7)]
    assert all(lo < hi for lo, hi in pairs)
    assert all(a[0] < b[0] and a[1] < b[1] for a, b in zip(pairs, pairs[1:]))
    for bad in (dict(dof=0), dict(dof=2.5), dict(dof=3, p_low=0.99, p_high=0.9),
                dict(dof=3, p_high=1.0)):
        with pytest.raises(ParameterError):
            ctfa_thresholds(**bad)


def test_schedule_matches_eq25_everywhere():
    Q_prev = 0.3 * QMAX + 0.7 * QMIN
    for q in [0.0, 1.0, 6.0, 6.2499, 6.25, 7.0, 8.8, 10.0, 11.35, 11.36, 20.0, 1e6]:
        assert np.allclose(scheduled_q(q, previous_weight=0.3),
                           paper_eq25(q, QMIN, QMAX, Q_prev), rtol=1e-14, atol=0)


def test_schedule_at_thresholds_below_and_above():
    assert np.array_equal(scheduled_q(PAPER_T1), QMIN)
    assert np.allclose(scheduled_q(PAPER_T2), QMAX, rtol=1e-15)
    assert np.array_equal(scheduled_q(3.0), QMIN)                        # Q_0 = Q_min
    Q_prev = 0.5 * (QMIN + QMAX)
    assert np.allclose(
        scheduled_q(3.0, previous_weight=0.5), Q_prev, rtol=1e-15
    )  # eq. 25: keep Q_{k-1}
    assert np.allclose(scheduled_q(50.0, previous_weight=0.5), QMAX, rtol=1e-15)
    assert ctfa_q_scale(3.0) == 0.0 and ctfa_q_scale(3.0, previous_weight=0.4) == 0.4
    assert ctfa_q_scale(PAPER_T1) == 0.0 and ctfa_q_scale(PAPER_T2) == 1.0
    assert ctfa_q_scale(1e9) == 1.0


def test_schedule_is_exactly_linear_between_thresholds():
    stats = np.linspace(PAPER_T1, PAPER_T2, 11)
    w = np.array([ctfa_q_scale(s) for s in stats])
    assert np.allclose(w, np.linspace(0.0, 1.0, 11), rtol=0, atol=1e-15)
    assert np.allclose(np.diff(w, 2), 0.0, atol=1e-15)
    Qs = np.array([scheduled_q(s) for s in stats])
    assert np.allclose(np.diff(Qs, 2, axis=0), 0.0, atol=1e-14 * QMAX.max())   # round-off only
    mid = scheduled_q(0.5 * (PAPER_T1 + PAPER_T2))
    assert np.allclose(mid, 0.5 * (QMIN + QMAX), rtol=1e-15)


def test_schedule_is_monotonic_and_bounded():
    stats = np.linspace(0.0, 30.0, 3001)
    w = np.array([ctfa_q_scale(s) for s in stats])
    assert np.all(np.diff(w) >= 0.0) and w.min() == 0.0 and w.max() == 1.0


def test_schedule_follows_eq25_with_memory():
    # the statistic sequence rises, falls below T1 (Q held), jumps above T2, falls, rises
    sequence = [8.0, 3.0, 12.0, 2.0, 7.0, 0.5, 11.0]
    expected_weights = [(8.0 - 6.25) / 5.1, (8.0 - 6.25) / 5.1, 1.0, 1.0,
                        (7.0 - 6.25) / 5.1, (7.0 - 6.25) / 5.1, (11.0 - 6.25) / 5.1]
    schedule = CtfaQSchedule(QMIN, QMAX)
    assert np.array_equal(schedule.Q, QMIN) and schedule.weight == 0.0
    Q_paper = QMIN                   # Q_0 = Q_min
    for q, w in zip(sequence, expected_weights):
        Q_paper = paper_eq25(q, QMIN, QMAX, Q_paper)
        Q = schedule.update(q)
        assert schedule.weight == pytest.approx(w, rel=1e-14)
        assert np.allclose(Q, Q_paper, rtol=1e-14)
    snapshot = copy.deepcopy(schedule)
    schedule.reset()
    assert np.array_equal(schedule.Q, QMIN) and snapshot.weight == pytest.approx(
        expected_weights[-1]
    )


def test_chi_square_statistic_matches_definition_and_ukf_nis():
    rng = np.random.default_rng(21)
    A = rng.normal(size=(3, 3))
    S = A @ A.T + 3.0 * np.eye(3)
    v = rng.normal(size=3)
    assert chi_square_statistic(v, S) == pytest.approx(v @ np.linalg.inv(S) @ v, rel=1e-12)
    ukf = UnscentedKalmanFilter(15, x0=rng.normal(size=15), P0=np.eye(15))
    H = np.hstack([np.eye(3), np.zeros((3, 12))])           # paper 000 eq. 4
    info = ukf.update(rng.normal(size=3), lambda x: H @ x, np.diag([2.56, 4.42, 3.43]) ** 2)
    assert chi_square_statistic(info["innovation"], info["S"]) == pytest.approx(
        info["nis"], rel=1e-12
    )


def test_chi_square_statistic_exceedance_rates():
    # under a correct model the statistic exceeds T1 with probability 10 % and T2 with 1 %
    rng = np.random.default_rng(22)
    A = rng.normal(size=(3, 3))
    S = A @ A.T + np.eye(3)
    L = np.linalg.cholesky(S)
    stats = np.array([chi_square_statistic(L @ rng.normal(size=3), S) for _ in range(20000)])
    T1, T2 = ctfa_thresholds(3)
    assert stats.mean() == pytest.approx(3.0, abs=0.1)
    assert (stats > T1).mean() == pytest.approx(0.10, abs=0.007)
    assert (stats > T2).mean() == pytest.approx(0.01, abs=0.0025)


def test_bad_arguments_raise_clear_errors():
    for bad in (-1.0, float("nan"), float("inf")):
        with pytest.raises(InputError, match="'stat'"):
            ctfa_q_scale(bad)
    with pytest.raises(ParameterError, match="thresholds"):
        ctfa_q_scale(5.0, T1=10.0, T2=5.0)
    with pytest.raises(ParameterError, match="shape"):
        CtfaQSchedule(QMIN, np.eye(2))
    with pytest.raises(ParameterError, match="positive semi-definite"):
        CtfaQSchedule(QMAX, QMIN)
    with pytest.raises(InputError, match="positive definite"):
        chi_square_statistic(np.ones(2), -np.eye(2))
    with pytest.raises(InputError, match="previous_weight"):
        ctfa_q_scale(1.0, previous_weight=1.5)


def test_pass_decay_returns_geometrically_to_qmin_and_one_is_the_paper():
    """Our pass_decay variant against its closed form: after an exceedance that sets the
    weight w0, n passing epochs leave w0 d^n; d = 1 reproduces eq. 25's hold exactly."""
    Qmin, Qmax = np.eye(2), 50.0 * np.eye(2)
    stats = [9.0] + [1.0] * 6 + [12.0, 0.5]
    w0 = (9.0 - PAPER_T1) / (PAPER_T2 - PAPER_T1)
    for d in (1.0, 0.6, 0.0):
        sched = CtfaQSchedule(Qmin, Qmax, pass_decay=d)
        weights = []
        for s in stats:
            sched.update(s)
            weights.append(sched.weight)
        expected = [w0] + [w0 * d ** n for n in range(1, 7)] + [1.0, d]
        np.testing.assert_allclose(weights, expected, rtol=1e-12, atol=0.0)
        np.testing.assert_allclose(sched.Q, Qmin + d * (Qmax - Qmin), rtol=1e-12)
    held = CtfaQSchedule(Qmin, Qmax)                 # default = the paper's eq. 25
    w = 0.0
    for s in stats:
        held.update(s)
        w = ctfa_q_scale(s, PAPER_T1, PAPER_T2, w)
        assert held.weight == w
    for bad in (-0.1, 1.5, float("nan")):
        with pytest.raises(ParameterError, match="pass_decay"):
            CtfaQSchedule(Qmin, Qmax, pass_decay=bad)


def null_mean_weight(T1, T2, dof, pass_decay):
    """Long-run mean weight of the schedule fed by a correct model (statistic chi2(dof) each
    epoch), by integration over the chi-square density: an exceedance q >= T1 (probability p)
    sets w = g(q) = min((q - T1) / (T2 - T1), 1), each pass multiplies it by d, so the weight
    is g of the last exceedance times d^age with P(age = a) = p (1 - p)^a:
    E[w] = E[g | q >= T1] p / (1 - (1 - p) d)."""
    from scipy import integrate, stats
    dist = stats.chi2(dof)
    p = dist.sf(T1)
    linear, _ = integrate.quad(lambda q: (q - T1) / (T2 - T1) * dist.pdf(q), T1, T2)
    mean_g = (linear + dist.sf(T2)) / p
    return mean_g * p / (1.0 - (1.0 - p) * pass_decay)


@pytest.mark.parametrize("pass_decay", [1.0, 0.5])
def test_schedule_under_a_correct_model_matches_the_chi_square_integral(pass_decay):
    """The Q a correct model leaves behind (docs/uav_maneuver.md, why eq. 25 cannot give a
    3x phase ratio): the schedule fed chi2(3) statistics against the integral above.  With
    eq. 25 as printed (d = 1) the mean weight is E[g | q >= 6.25] = 0.394, so the calm-flight
    Q averages 1 + 0.394 (k - 1) Qmin and no manoeuvre (Q <= Qmax = k Qmin) can raise the mean
    more than k / (1 + 0.394 (k - 1)) < 1 / 0.394 = 2.54 times; with d = 0.5 the floor is 0.072."""
    rng = np.random.default_rng(5)
    sched = CtfaQSchedule(np.eye(1), 300.0 * np.eye(1), pass_decay=pass_decay)
    weights = np.empty(40000)
    for i, q in enumerate(rng.chisquare(3, size=weights.size)):
        sched.update(q)
        weights[i] = sched.weight
    expected = null_mean_weight(PAPER_T1, PAPER_T2, 3, pass_decay)
    assert weights[100:].mean() == pytest.approx(expected, rel=0.04)
    if pass_decay == 1.0:
        assert expected == pytest.approx(0.394, abs=0.001)
        assert 300.0 / (1.0 + 299.0 * expected) < 2.6        # the ceiling of the phase ratio
    else:
        assert expected == pytest.approx(0.0717, abs=0.001)
