"""One effect core for ``diagnose`` and ``explain``: a physical law the rig model
may be missing, declared once.

- :mod:`~hybridtable.effects.spec`: the model an effect changes
  (:class:`ModelSpec`) and the scale of a rig (:class:`RigScale`);
- :mod:`~hybridtable.effects.effect`: what an effect is (:class:`Effect`, its
  :class:`EffectParameter` with unit, bounds, typical change and null);
- :mod:`~hybridtable.effects.library`: the built-in effects, one module each;
- :mod:`~hybridtable.effects.registry`: name -> effect, plug-ins and the
  entry-point group ``hybridtable.effects``.
"""

from hybridtable._lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "spec": ("ModelSpec", "RigScale", "LoopChange"),
        "effect": ("Effect", "EffectParameter", "Signature", "STAGES", "FRONT_ENDS"),
        "registry": (
            "effect_names",
            "get_effect",
            "load_plugin",
            "parse_effect_spec",
            "register_effect",
        ),
    },
)
