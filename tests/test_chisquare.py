"""navcore.chisquare against scipy.stats.chi2 (bit for bit) and printed chi-square tables."""
import numpy as np
import pytest
from scipy import stats

from navcore.chisquare import chi2

PROBABILITIES = np.concatenate([np.linspace(1e-6, 1 - 1e-6, 199),
                                [0.001, 0.01, 0.02, 0.05, 0.1, 0.5, 0.9, 0.95, 0.99]])


@pytest.mark.parametrize("dof", [1, 2, 3, 6, 15])
def test_quantiles_are_bit_identical_to_scipy_stats(dof):
    for p in PROBABILITIES:
        assert float(chi2.ppf(float(p), dof)) == float(stats.chi2.ppf(float(p), dof))
        assert float(chi2.isf(float(p), dof)) == float(stats.chi2.isf(float(p), dof))


@pytest.mark.parametrize("dof, p, table", [
    # upper-tail critical values as printed in chi-square tables (4 significant decimals)
    (1, 0.01, 6.6349), (1, 0.05, 3.8415), (3, 0.10, 6.2514), (3, 0.01, 11.3449),
    (6, 0.05, 12.5916), (15, 0.01, 30.5779),
])
def test_upper_quantiles_match_printed_tables(dof, p, table):
    assert chi2.isf(p, dof) == pytest.approx(table, abs=6e-5)
    assert chi2.ppf(1.0 - p, dof) == pytest.approx(table, abs=6e-5)
