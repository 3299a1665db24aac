"""Explain a measured CoR table (``hybridtable explain``): which loop is
consistent with it, what it determines, and what it cannot say
(``docs/explain.md``).

- :mod:`~hybridtable.explain.conditions`: what a row states;
- :mod:`~hybridtable.explain.table`: the CSV, its rows and its noise;
- :mod:`hybridtable.effects` (below this package, shared with ``diagnose``):
  what may differ on the rig (:mod:`~hybridtable.explain.effects` keeps the
  old import path);
- :mod:`~hybridtable.explain.model`: the CoR of each row under effects (the
  fast engine, or the Drake diagram for systems it does not carry);
- :mod:`~hybridtable.explain.fit`: fits of 1-3 effects, ranked by BIC;
- :mod:`~hybridtable.explain.identify`: the SVD of the sensitivities, in words;
- :mod:`~hybridtable.explain.patterns`: interaction, first-order readings, trends;
- :mod:`~hybridtable.explain.separate`: look-alikes and the run that separates them;
- :mod:`~hybridtable.explain.explain`: all of it, and the verdict.
"""

from hybridtable._lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "conditions": ["Conditions", "PAPER_CONDITIONS"],
        "table": ["CorTable", "CorRow", "read_cor_table", "cor_table"],
        "effects": [
            "CorEffect",
            "CorParameter",
            "register_cor_effect",
            "cor_effect_names",
            "get_cor_effect",
        ],
        "explain": ["Explanation", "explain_table"],
    },
)
