"""Thresholds and constants of ``diagnose`` (significance, noise floors, ties)."""

from __future__ import annotations

__all__ = [
    "BIC_THRESHOLD",
    "Z_THRESHOLD",
    "INDISTINGUISHABLE_BIC",
    "CHANNELS",
    "FIT_ACCURACY",
    "NUMERICAL_FLOOR",
    "CLOSED_LOOP_FLOOR",
    "FAILED_RESIDUAL",
    "TIE_BIC",
    "MIN_EXCESS_REMOVED",
    "EXPLAINED_MAX_ERROR",
    "PAIR_POOL",
]


#: Smallest ``delta_bic`` of a significant effect (Kass & Raftery: > 10 is
#: very strong evidence).
BIC_THRESHOLD = 10.0


#: Smallest leave-one-run-out ``z`` of a significant effect.
Z_THRESHOLD = 3.0


#: Two significant effects whose ``delta_bic`` differ by less are
#: indistinguishable on the data (< 6: no strong evidence for either).
INDISTINGUISHABLE_BIC = 6.0


#: Replay channels and their units.
CHANNELS: dict[str, str] = {"f_mea_n": "N", "p_act_m": "m"}


#: Integrator accuracy of the fits (RK3; 1e-3 N and 2e-8 m of error on the
#: examples, far under the noise).
FIT_ACCURACY = 1e-5


#: Noise floor of a noise-free record, relative to the largest reading (force)
#: or the range (position): the fits' numerical resolution.
NUMERICAL_FLOOR = 1e-5


#: Smallest force error (in units of the force noise) the closed loop's
#: velocity residual is credited with: below it, errors are numerical.
CLOSED_LOOP_FLOOR = 1e-3


#: Residual value standing in for a model run that failed during a fit.
FAILED_RESIDUAL = 1e3


#: ``delta_bic`` differences below this are ties (a likelihood ratio of 1.3).
TIE_BIC = 0.5


#: Smallest fraction of the held-out excess error (held-out error minus the
#: noise floor, 1) an effect must remove to enter the model: a significant
#: effect that leaves the error where it was does not explain the data.
MIN_EXCESS_REMOVED = 0.25


#: Largest held-out error (noise units) of a model called ``explained``.
EXPLAINED_MAX_ERROR = 1.3


#: First-round candidates (by ``delta_bic``) whose pairs are fitted jointly
#: when forward selection leaves the end test failing.
PAIR_POOL = 4
