"""What ``explain`` says and draws: the verdict, the models, what the table determines."""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["format_explanation", "plot_explanation"]


def format_explanation(expl, top: int = 6) -> str:
    """The lines after the verdict: noise, models, identifiable, unresolved, patterns."""
    d = expl.to_dict()
    lines = [
        f"noise: {d['noise']['source']}, plus the model's own "
        f"{d['noise']['model_error_ln_cor']:g} in ln CoR"
    ]
    assumed = [k for k, v in d["stated"].items() if "assumed" in v]
    if assumed:
        lines.append(
            "assumed (the paper's Table 1, not stated by the table or a flag): "
            + ", ".join(assumed)
        )
    lines.append("")
    lines.append(f"{'model':58s} {'RMS CoR':>8s} {'chi2':>9s} {'dof':>3s} {'BIC':>9s}  values")
    for m in d["models"][:top]:
        vals = ", ".join(f"{k} {v:.4g}" for k, v in m["values"].items())
        lines.append(
            f"{m['name']:58s} {m['rms_cor']:8.4f} {m['chi2']:9.3g} {m['dof']:3d} {m['bic']:9.3g}  {vals}"
        )
    if d["not_fitted"]:
        lines.append(
            f"not fitted ({len(d['not_fitted'])} model(s)): as many parameters as the table has "
            "rows, or more"
        )
    if d["flat"]:
        f = d["flat"]
        cor = ", ".join(f"{k} {v:.4f}" for k, v in f["cor"].items())
        beats = f["best_model_beats_it"]
        lines.append(
            f"a flat CoR per compensator ({cor}) gives RMS {f['rms_cor']:.4f}; "
            + ("the best model beats it" if beats else "no model beats it significantly")
        )
    lines.append("")
    lines.append(
        "the table determines: "
        + (
            "; ".join(
                f"{i['combination']} (to {100 * i['std']:.2g} %)"
                if i["relative"]
                else f"{i['combination']} (to {i['std']:.2g})"
                for i in d["identifiable"]
            )
            or "no named combination"
        )
    )
    for u in d["unresolved"]:
        lines.append(f"  cannot resolve: {u['words']}")
    for r in d["readings"]:
        for w in r["words"]:
            lines.append(f"  reading: {w}")
    for t in d["trends"]:
        lines.append(f"  trend: {t['words']}")
    for s in d["separating_runs"]:
        lines.append(f"  to separate: {s['words']}")
    for u in d["unexplained"]:
        lines.append(f"  not explained by the loop model: {u}")
    return "\n".join(lines)


def plot_explanation(expl, path: str | Path, top: int = 3) -> Path:
    """Measured CoR of each row (with its noise) against the best models' CoR."""
    import matplotlib.pyplot as plt

    from hybridtable.reports.figures import save_figure

    fig, ax = plt.subplots(figsize=(8, 4.5))
    rows = expl.table.rows
    x = np.arange(len(rows))
    cor = np.array([r.cor for r in rows])
    ax.errorbar(
        x, cor, yerr=expl.sigma_ln * cor, fmt="ko", capsize=3, label="measured (noise 1 std)"
    )
    for k, fit in enumerate(expl.fits[:top]):
        ax.plot(
            x + 0.1 * (k + 1),
            fit.predicted_cor,
            "s",
            ms=5,
            label=f"{fit.name} (RMS {fit.rms_cor:.3g})",
        )
    ax.set_xticks(x, [r.label for r in rows], rotation=30, ha="right", fontsize=8)
    ax.set_xlabel("row [compensator (CSV line)]")
    ax.set_ylabel("CoR [1]")
    ax.axhline(1.0, color="0.7", lw=0.8)
    ax.legend(fontsize=7)
    ax.set_title("measured CoR and the best models")
    return save_figure(fig, path)
