"""Chi-square quantiles for the filters' gates, from ``scipy.special`` instead of ``scipy.stats``.

``chi2.ppf`` and ``chi2.isf`` evaluate the same special functions as ``scipy.stats.chi2`` for
a probability strictly inside (0, 1) (``2 gammaincinv(dof/2, p)`` and ``chdtri(dof, alpha)``),
so the numbers are bit for bit those of ``scipy.stats.chi2`` (tests/test_chisquare.py).

Why not ``scipy.stats`` itself: everything navcore imports ends up inside the FMUs, and
``scipy.stats`` loads ``scipy.fft`` and the C++ extension ``scipy._lib._uarray``, which keeps
Python references in C++ objects of static storage duration.  A native FMI host that ends
with ``exit()`` runs those static destructors first and only then pythonfmu's teardown of the
embedded interpreter (``Py_FinalizeEx``), which releases the same references a second time
and frees live objects: a crash at exit in about half of all native-host runs.  Keep
``scipy.stats`` (and ``scipy.fft``) out of navcore; ``tests/test_chost.py`` checks the import
chain of every FMU.
"""
from __future__ import annotations

from scipy import special


class _ChiSquare:
    """The two quantile functions of the chi-square distribution that navcore uses."""

    @staticmethod
    def ppf(p, dof):
        """Lower quantile: the x with P(X <= x) = p for X ~ chi2(dof), 0 < p < 1."""
        return 2.0 * special.gammaincinv(dof / 2, p)

    @staticmethod
    def isf(alpha, dof):
        """Upper quantile: the x with P(X > x) = alpha for X ~ chi2(dof), 0 < alpha < 1."""
        return special.chdtri(dof, alpha)


#: drop-in for the ``scipy.stats.chi2`` methods navcore calls (``ppf``, ``isf``)
chi2 = _ChiSquare()
