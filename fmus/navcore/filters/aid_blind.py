"""A law that judges the fixes (a robust test, an adaptation on their innovations) judges
them against the covariance the fixes alone leave: the land aids' updates since the last fix
are left out of it.

A land aid (ZUPT, ZARU, NHC: :mod:`navcore.filters.land_aids`) is an assumption about the
vehicle, not a measurement, and its updates shrink P.  A robust law that tests each fix
against ``S = H P H' + R`` (NewtonRobustKf's per-observation chi-square test, paper 004; the
IGG-III weights) would then test the fix against what the aids assumed: where the
assumption is not exact (an NHC whose mounting is a degree off, a car that slips sideways
at 0.1 m/s, a rest that is not quite one) the INS's real errors outgrow the shrunk P, good
fixes fail the test and are withheld from the INS that needs them.  On the shared car drive
with ZUPT, ZARU and NHC at their default sigmas, NewtonRobustKf rejected runs of RTK fixes
after each outage and between them, and its error in the outages was twice the Kf's.  An
adaptive law reads the same statistic: CTFA's chi-square (paper 000 eq. 24) took good fixes
for a model mismatch and held Q near its maximum through the outages, and the IMM's
likelihoods leant to its large-Q model.

So the law sees ``P_blind``: the covariance propagated from the last fix's update over
the same IMU intervals, without the aids' updates since (at each aid update,
``P_blind <- Phi_acc P_blind Phi_acc' + Q_acc`` with the accumulators the update then
restarts; after a fix, ``P_blind = P``; a UKF's ``P_blind`` is predicted by its own
unscented time update, with its filters: ``UnscentedAidBlind`` of
:mod:`navcore.filters.ukf_filters`).  A Kalman update never increases the covariance, so
``P_blind >= P``: the covariance of the INS and the fixes alone, what the law tested before
the aids existed.  An aid can thus never make a fix look faulty, nor move a CTFA Q or the
IMM's model probabilities where the fixes alone would not.  The fix's update itself uses the
aided P (the aids' information is used; only the law's verdict ignores it), and the recovery
guards' inflation is sized on it as before.  Without aid updates ``P_blind`` is
the prediction itself: the law as it was.  (Groves 2013, *Principles of GNSS, Inertial, and
Multisensor Integrated Navigation Systems*, 2nd ed., sec. 17.3.1: an innovation test is only
as good as the covariance it is measured against; the aids are the filter's own
assumptions, not independent information on the fix.)
"""
from __future__ import annotations

from abc import ABC, abstractmethod

from .array_checks import symmetrize
from .ins_gnss_kf import predicted_rows


class AidBlindCovariance(ABC):
    """Mixin of an engine whose law judges the fixes (module docstring): keeps ``blind_P``,
    None while no aid has updated since the last fix, else the covariance without the aids'
    updates since (the engine's :meth:`blind_now` gives it at an aid's update; an engine whose
    time update moves its covariance between updates propagates it there too).  List it
    before the engine's base class; the engine calls :meth:`init_blind` once and
    :meth:`fix_taken` after each fix's update."""

    state_fields = ("blind_P",)

    def init_blind(self):
        self.blind_P = None

    def aid_update(self, H, z, R):
        blind = self.blind_now()
        super().aid_update(H, z, R)
        self.blind_P = blind

    @abstractmethod
    def blind_now(self):
        """The covariance without the aids since the last fix, now, before an aid's update
        (``blind_P`` carried to now, or the engine's own covariance when None); each family
        carries it its own way (:class:`AidBlindTest`, ``UnscentedAidBlind``)."""

    def fix_taken(self):
        """After a fix's update: the covariance is the fixes' again."""
        self.blind_P = None


class AidBlindTest(AidBlindCovariance):
    """:class:`AidBlindCovariance` of a Kf-family engine, whose covariance moves only at an
    update (the prediction since is in its accumulators): the engine calls
    :meth:`tested_prediction` for its test."""

    def blind_now(self):
        start = self.P if self.blind_P is None else self.blind_P
        return symmetrize(predicted_rows(start, self.phi_acc) + self.q_acc)

    def tested_prediction(self, P_pred):
        """The prediction the law tests a fix against: ``P_pred`` (the engine's own) when no
        aid updated since the last fix, else ``P_blind`` propagated to now."""
        if self.blind_P is None:
            return P_pred
        return predicted_rows(self.blind_P, self.phi_acc) + self.q_acc


__all__ = ["AidBlindCovariance", "AidBlindTest"]
