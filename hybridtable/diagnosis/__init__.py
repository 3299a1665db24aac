"""Which physical effect is the rig model missing (``hybridtable diagnose``).

- :mod:`~hybridtable.effects.effect`: what an effect is (:class:`Effect`,
  its parameters and bounds, the :class:`ModelSpec` it changes);
- :mod:`~hybridtable.effects.library`: the built-in effects;
  :mod:`~hybridtable.effects.registry`: name -> effect;
- :mod:`~hybridtable.diagnosis.evaluate`: a model against the runs, residuals
  prewhitened with each run's noise model;
- :mod:`~hybridtable.diagnosis.fit`: least-squares fits, BIC, leave-one-run-out;
- :mod:`~hybridtable.diagnosis.candidates`: the evidence of each candidate, ranking;
- :mod:`~hybridtable.diagnosis.design`: the run that would separate look-alikes;
- :mod:`~hybridtable.diagnosis.diagnose`: :func:`diagnose`, the forward selection;
- :mod:`~hybridtable.diagnosis.add_effect`: the model with effects added
  (fitted where not given), compared with the runs (``compare --add``);
- :func:`~hybridtable.diagnosis.diagnose.model_from_diagnosis`: the model
  a diagnosis found, as the effect core's model file
  (:mod:`~hybridtable.effects.model_file`: ``--save-model``, ``--model``);
- :mod:`~hybridtable.diagnosis.settings`: thresholds.
"""

from hybridtable._lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "add_effect": ("compare_with_model", "model_with_effects"),
        "candidates": (
            "Candidate",
            "Diagnosis",
        ),
        "diagnose": ("diagnose", "model_from_diagnosis"),
        "effects": (
            "Effect",
            "EffectParameter",
            "ModelSpec",
            "RigScale",
            "Signature",
            "effect_names",
            "get_effect",
            "load_plugin",
            "parse_effect_spec",
            "register_effect",
            "FittedEffect",
            "RigModel",
            "load_model",
        ),
        "fit": ("fit_effect", "fit_given"),
    },
)
