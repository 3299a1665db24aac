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
- :mod:`~hybridtable.diagnosis.model_file`: the model as a file
  (``--save-model``, ``--model``);
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
        "diagnose": ("diagnose",),
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
        ),
        "fit": ("fit_effect", "fit_given"),
        "model_file": ("FittedEffect", "RigModel", "model_from_diagnosis"),
        "model_reader": ("load_model",),
    },
)
