"""What ``compare`` and ``diagnose`` do alike with 6-DoF runs
(``hybridtable-run6/1``): refuse the options of 1-D runs, load the plug-ins,
read the runs through the log's mapping and check the outputs."""

from __future__ import annotations

import argparse
from collections.abc import Mapping

from hybridtable.errors import CommandError

__all__ = ["read_run6_arguments", "require_apply6"]


def read_run6_arguments(
    args: argparse.Namespace,
    one_d_only: Mapping[str, object],
    folders: Mapping | None = None,
    files: Mapping | None = None,
):
    """Refuse every option of ``one_d_only`` (name -> default) the user gave,
    register ``--plugin``'s effects, read every run of ``RUN...`` (all
    defects before any work) and check ``--json``, the output ``files`` and
    ``folders`` (flag -> path): ``(runs, layout)``."""
    from hybridtable.commands._common import check_outputs, log_layout_of
    from hybridtable.commands._model_options import load_plugins
    from hybridtable.six_dof.run6 import RUN6_COLUMNS, read_runs6

    for name, default in one_d_only.items():
        if getattr(args, name, default) not in (default, (), []):
            flag = "--" + name.replace("_", "-")
            raise CommandError(f"{flag} is not available for 6-DoF runs (hybridtable-run6/1) yet")
    load_plugins(args)
    layout = log_layout_of(args, RUN6_COLUMNS)
    runs = read_runs6(args.runs, layout)
    inputs = [p.resolve() for r in runs for p in (r.csv_path, r.json_path) if p is not None]
    check_outputs(args, inputs, files={"--json": args.json, **(files or {})}, folders=folders)
    return runs, layout


def require_apply6(effect, flag: str) -> None:
    """Refuse an effect of the 1-D loop only, named by ``flag``."""
    if effect.apply6 is None:
        raise CommandError(
            f"{flag} {effect.name}: the effect acts on the 1-D loop only (hybridtable effects, "
            "column loops, lists those of a six-axis rig)"
        )
