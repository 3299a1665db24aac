"""The colour scale of a campaign's maps."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from hybridtable.reports.colour_scale import colour_scale, crosses, ticks_both_sides  # noqa: E402


def test_a_cor_map_has_ticks_on_both_sides_of_one():
    """CoRs from 0.99 to 1.16: centred on 1 (red above: energy created), with
    ticks above 1.000 as well as below."""
    values = np.array([0.99, 1.0, 1.05, 1.16])
    norm, cmap = colour_scale(values, 1.0, True)
    assert cmap == "RdBu_r" and norm.vcenter == 1.0
    fig, ax = plt.subplots()
    mesh = ax.pcolormesh(values.reshape(2, 2), norm=norm, cmap=cmap)
    bar = fig.colorbar(mesh, ax=ax)
    ticks_both_sides(bar, norm)
    ticks = bar.get_ticks()
    plt.close(fig)
    assert ticks.min() < 1.0 < ticks.max()
    assert np.isclose(ticks, 1.0).any()


def test_values_on_one_side_of_the_level_are_not_centred():
    norm, cmap = colour_scale(np.array([1.01, 1.2]), 1.0, True)
    assert cmap == "viridis" and not hasattr(norm, "vcenter")
    assert colour_scale(np.array([0.2, 0.4]), None, True, fraction=True)[1] == "RdYlGn"
    assert (
        crosses(1.0, [0.9, np.nan, 1.1])
        and not crosses(1.0, [1.1, 1.2])
        and not crosses(None, [0, 2])
    )
