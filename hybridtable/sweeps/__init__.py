"""Campaigns: grids and Monte Carlo draws of the loop, run on Dask
(``hybridtable sweep SPEC.toml``).

- :mod:`.spec`: the TOML spec, checked (one line naming the key), and its runs;
- :mod:`.inputs`: what a spec can vary and how a run becomes the loop's parameters;
- :mod:`.distributions`: uniform, log-uniform, normal, a user's list;
- :mod:`.metrics`: what a run measures (simulation, margins);
- :mod:`.runner`: one run -> one row, never raising;
- :mod:`.store`: the Parquet file (a row per run, the spec in its metadata);
- :mod:`.engine`: the Dask client, tasks, checkpoints, resume, Ctrl-C.
"""

from hybridtable._lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "plan": ("SweepSpec", "RunInputs"),
        "spec": ("load_spec", "parse_spec"),
        "engine": ("CampaignResult", "run_campaign"),
        "runner": ("run_one",),
        "store": ("read_results", "write_results"),
    },
)
