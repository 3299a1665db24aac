"""Reports: text tables, figures (matplotlib, units on every axis) and Markdown.

One module per command that writes a report, each with its own
``write_report``: :mod:`~hybridtable.reports.compare`,
:mod:`~hybridtable.reports.diagnose`, :mod:`~hybridtable.reports.margins`,
:mod:`~hybridtable.reports.compensators` (the margins figures are in
:mod:`~hybridtable.reports.margin_plots`); :mod:`~hybridtable.reports.reproduce`
runs the paper's tables and draws its figures; :mod:`~hybridtable.reports.figures`
holds the figures of simulated runs. Import the module you need (they load
matplotlib).
"""

__all__: list[str] = []
