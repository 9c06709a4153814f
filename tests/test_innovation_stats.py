"""navcore.filters.innovation_stats: the NIS in its two arithmetic forms against the definition, and
the chi-square quantiles against scipy.stats.chi2 (bit for bit) and printed tables."""
import numpy as np
import pytest
from scipy import stats

from navcore.core.component import InputError, ParameterError
from navcore.filters.innovation_stats import (CHI2_THRESHOLD_PAPER_004, CTFA_THRESHOLDS_PAPER_000,
                                      checked_cholesky, chi2_gate, chi2_lower_quantile,
                                      chi2_upper_quantile, chi_square_statistic,
                                      gaussian_log_likelihood, log_det_from_cholesky, nis,
                                      nis_from_cholesky)

PROBABILITIES = np.concatenate([np.linspace(1e-6, 1 - 1e-6, 199),
                                [0.001, 0.01, 0.02, 0.05, 0.1, 0.5, 0.9, 0.95, 0.99]])


@pytest.mark.parametrize("dof", [1, 2, 3, 6, 15])
def test_quantiles_are_bit_identical_to_scipy_stats(dof):
    for p in PROBABILITIES:
        assert float(chi2_lower_quantile(float(p), dof)) == float(stats.chi2.ppf(float(p), dof))
        assert float(chi2_upper_quantile(float(p), dof)) == float(stats.chi2.isf(float(p), dof))


@pytest.mark.parametrize("dof, p, table", [
    # upper-tail critical values as printed in chi-square tables (4 significant decimals)
    (1, 0.01, 6.6349), (1, 0.05, 3.8415), (3, 0.10, 6.2514), (3, 0.01, 11.3449),
    (6, 0.05, 12.5916), (15, 0.01, 30.5779),
])
def test_upper_quantiles_match_printed_tables(dof, p, table):
    assert chi2_upper_quantile(p, dof) == pytest.approx(table, abs=6e-5)
    assert chi2_lower_quantile(1.0 - p, dof) == pytest.approx(table, abs=6e-5)
    assert chi2_gate(p, dof) == pytest.approx(table, abs=6e-5)


def test_papers_gates_are_the_printed_roundings_of_the_quantiles():
    assert CHI2_THRESHOLD_PAPER_004 == 6.635 and round(chi2_gate(0.01, 1), 3) == 6.635
    t1, t2 = CTFA_THRESHOLDS_PAPER_000
    assert (t1, t2) == (6.25, 11.35)
    assert round(chi2_lower_quantile(0.90, 3), 2) == t1
    assert abs(chi2_lower_quantile(0.99, 3) - t2) < 0.006      # 11.3449, printed rounded up
    with pytest.raises(ParameterError, match="alpha"):
        chi2_gate(0.0, 1)
    with pytest.raises(ParameterError, match="dof"):
        chi2_gate(0.05, 1.5)


def _case(seed, m=6):
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(m, m))
    return rng.normal(size=m), A @ A.T + 0.5 * np.eye(m)


def test_both_nis_forms_equal_the_definition_with_the_explicit_inverse():
    for seed in range(20):
        v, S = _case(seed)
        definition = v @ np.linalg.inv(S) @ v
        assert nis(v, S) == pytest.approx(definition, rel=1e-11)
        v_checked, L = checked_cholesky(v, S, "test")
        assert nis_from_cholesky(L, v_checked) == pytest.approx(definition, rel=1e-11)
        assert chi_square_statistic(v, S) == pytest.approx(definition, rel=1e-11)
        # and it is the Cholesky form itself, to the bit (pins the delegation, not the value)
        assert chi_square_statistic(v, S) == nis_from_cholesky(L, v_checked)
        assert nis_from_cholesky(L, v_checked, general_solve=True) == pytest.approx(
            definition, rel=1e-11)


def test_log_likelihood_pieces_match_scipy_multivariate_normal():
    v, S = _case(3, m=3)
    _, L = checked_cholesky(v, S, "test")
    assert log_det_from_cholesky(L) == pytest.approx(np.linalg.slogdet(S)[1], rel=1e-12)
    expected = stats.multivariate_normal(mean=np.zeros(3), cov=S).logpdf(v)
    assert gaussian_log_likelihood(nis_from_cholesky(L, v), log_det_from_cholesky(L), 3) \
        == pytest.approx(expected, rel=1e-12)


def test_checked_statistic_names_the_caller_and_the_problem():
    with pytest.raises(InputError, match="where: 'S' must be 2x2"):
        checked_cholesky(np.ones(2), np.eye(3), "where")
    with pytest.raises(InputError, match="must be finite"):
        checked_cholesky([1.0, np.nan], np.eye(2), "where")
    with pytest.raises(InputError, match="not positive definite"):
        chi_square_statistic(np.ones(2), -np.eye(2))
