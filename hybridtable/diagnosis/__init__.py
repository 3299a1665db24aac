"""Which physical effect is the rig model missing (``hybridtable diagnose``).

- :mod:`~hybridtable.diagnosis.effects`: what an effect is (:class:`Effect`,
  its parameters and bounds, the :class:`ModelSpec` it changes);
- :mod:`~hybridtable.diagnosis.library`: the built-in effects;
  :mod:`~hybridtable.diagnosis.registry`: name -> effect;
- :mod:`~hybridtable.diagnosis.evaluate`: a model against the runs, residuals
  prewhitened with each run's noise model;
- :mod:`~hybridtable.diagnosis.fit`: least-squares fits, BIC, leave-one-run-out;
- :mod:`~hybridtable.diagnosis.candidates`: the evidence of each candidate, ranking;
- :mod:`~hybridtable.diagnosis.design`: the run that would separate look-alikes;
- :mod:`~hybridtable.diagnosis.diagnose`: :func:`diagnose`, the forward selection;
- :mod:`~hybridtable.diagnosis.add_effect`: the model with one effect, compared
  with the runs (``compare --add``);
- :mod:`~hybridtable.diagnosis.settings`: thresholds.
"""

from hybridtable.diagnosis.add_effect import compare_with_effect
from hybridtable.diagnosis.candidates import Candidate, Diagnosis
from hybridtable.diagnosis.diagnose import diagnose
from hybridtable.diagnosis.effects import Effect, EffectParameter, ModelSpec, RigScale, Signature
from hybridtable.diagnosis.fit import fit_effect
from hybridtable.diagnosis.registry import (
    effect_names,
    get_effect,
    parse_effect_spec,
    register_effect,
)

__all__ = [
    "Candidate",
    "Diagnosis",
    "Effect",
    "EffectParameter",
    "ModelSpec",
    "RigScale",
    "Signature",
    "compare_with_effect",
    "diagnose",
    "effect_names",
    "fit_effect",
    "get_effect",
    "parse_effect_spec",
    "register_effect",
]
