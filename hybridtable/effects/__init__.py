"""One effect core for ``diagnose`` and ``explain``: a physical law the rig model
may be missing, declared once.

- :mod:`~hybridtable.effects.spec`: the model an effect changes
  (:class:`ModelSpec`) and the scale of a rig (:class:`RigScale`);
- :mod:`~hybridtable.effects.effect`: what an effect is (:class:`Effect`, its
  :class:`EffectParameter` with unit, bounds, typical change and null);
- :mod:`~hybridtable.effects.library`: the built-in effects, one module each;
- :mod:`~hybridtable.effects.registry`: name -> effect, plug-ins and the
  entry-point group ``hybridtable.effects``;
- :mod:`~hybridtable.effects.fitting`: the one fit of effects to data (least
  squares in each parameter's coordinate, standard errors);
- :mod:`~hybridtable.effects.selection`: the one rule for choosing among fitted
  models (BIC, look-alikes, the separating run);
- :mod:`~hybridtable.effects.search`: the one search for models of several
  effects (the combinations a screen ranks best, those of the best single
  effects, swaps);
- :mod:`~hybridtable.effects.workers`: the forked worker pool of the fits;
- :mod:`~hybridtable.effects.model_file` and
  :mod:`~hybridtable.effects.model_reader`: the model a front end found, as a
  file (``--save-model``, ``--model``), whose effect entries a six-axis
  rig's model file shares.

``diagnose`` (recorded runs) and ``explain`` (a CoR table) are front ends over
these: each keeps its data, its noise model, its screen and its words.
"""

from hybridtable._lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "spec": ("ModelSpec", "RigScale", "LoopChange"),
        "effect": ("Effect", "EffectParameter", "Signature", "STAGES", "FRONT_ENDS"),
        "model_file": ("FittedEffect", "RigModel"),
        "model_reader": ("load_model",),
        "registry": (
            "effect_names",
            "get_effect",
            "load_plugin",
            "parse_effect_spec",
            "register_effect",
        ),
    },
)
