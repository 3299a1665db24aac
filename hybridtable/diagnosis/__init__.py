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

from hybridtable._lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "add_effect": ("compare_with_effect",),
        "candidates": (
            "Candidate",
            "Diagnosis",
        ),
        "diagnose": ("diagnose",),
        "effects": (
            "Effect",
            "EffectParameter",
            "ModelSpec",
            "RigScale",
            "Signature",
        ),
        "fit": ("fit_effect",),
        "registry": (
            "effect_names",
            "get_effect",
            "parse_effect_spec",
            "register_effect",
        ),
    },
)
