"""Your own contact law in the Table 1 loop: a Hunt-Crossley contact LeafSystem.

1. `HuntCrossleyContact`, a pydrake LeafSystem with the contact's ports: input
   `motion` (3: p m, v m/s, a m/s^2; p > 0 penetrates), outputs `force` (1, N)
   and `force_rate` (1, N/s); f = k p^n (1 + d v) while p > 0 and f > 0, else 0.
2. `add_hybrid_loop(builder, params, contact=...)` swaps it in for the
   library's linear spring; a pydrake Simulator runs each loop.
3. Prints a verdict, then each compensator's CoR with the library's contact,
   yours at n = 1, d = 0 (the library's law: a check of the ports) and yours
   as asked (on an ideal rig, the law's own CoR). Writes `--out`/contact.png.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import matplotlib.pyplot as plt
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder, LeafSystem

import hybridtable
from hybridtable.studies import paper


class HuntCrossleyContact(LeafSystem):
    """f = k p^n (1 + d v) for penetration p > 0 (k in N/m^n, d in s/m), never pulling."""

    def __init__(self, stiffness_n_per_m_n: float, exponent: float, dissipation_s_per_m: float):
        super().__init__()
        self.k, self.n, self.d = stiffness_n_per_m_n, exponent, dissipation_s_per_m
        self.DeclareVectorInputPort("motion", 3)
        for i, name in enumerate(("force", "force_rate")):  # N, N/s: the law's (f, df/dt)
            self.DeclareVectorOutputPort(name, 1, lambda c, y, i=i: y.SetAtIndex(0, self.law(c)[i]))

    def law(self, context) -> tuple[float, float]:
        """(f [N], d f / dt [N/s]) at the input's motion."""
        p_m, v_m_per_s, a_m_per_s2 = self.get_input_port().Eval(context)
        k_p_n = self.k * max(p_m, 0.0) ** self.n
        force_n = k_p_n * (1.0 + self.d * v_m_per_s)
        if p_m <= 0.0 or force_n <= 0.0:
            return 0.0, 0.0
        rate_n_per_s = self.n * k_p_n / p_m * v_m_per_s * (1.0 + self.d * v_m_per_s)
        return force_n, rate_n_per_s + k_p_n * self.d * a_m_per_s2


def run(params: hybridtable.HybridLoopParams, contact=None) -> hybridtable.SimulationResult:
    """The loop with ``contact`` (None: the library's) in a new diagram, through the contact."""
    builder = DiagramBuilder()
    loop = hybridtable.add_hybrid_loop(builder, params, contact=contact)
    simulator = Simulator(builder.Build())
    context = simulator.get_mutable_context()
    loop.set_initial_conditions(context)
    simulator.AdvanceTo(1.0 / params.contact_frequency_hz)  # the contact lasts about half
    # collect_result refuses a record that ends while a force acts.
    result = hybridtable.collect_result(loop, context)
    return result


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    parser.add_argument("--exponent", type=float, default=1.5, help="n [1] (1.5: Hertz)")
    parser.add_argument("--dissipation-s-per-m", type=float, default=0.2, help="d [s/m]")
    parser.add_argument("--quick", action="store_true", help="only none and SDMDC")
    parser.add_argument(
        "--out", type=Path, default=Path("out/diagrams/custom_contact"), help="output folder"
    )
    parser.add_argument("--force", action="store_true", help="replace existing outputs")
    args = parser.parse_args(argv)
    figure_path = args.out / "contact.png"
    if figure_path.exists() and not args.force:
        parser.exit(2, f"refusing to replace {figure_path} (give --force)\n")
    names = ("none", "SDMDC") if args.quick else hybridtable.COMPENSATORS
    table1 = paper.table1_params("none")
    k_n_per_m = table1.contact_stiffness_n_per_m  # yours: k p^n = k_n_per_m p at p = v0 / omega
    p_peak_m = table1.initial_velocity_m_per_s / (2.0 * math.pi * table1.contact_frequency_hz)
    yours = (k_n_per_m * p_peak_m ** (1.0 - args.exponent), args.exponent, args.dissipation_s_per_m)
    ideal_rig = table1.with_(sensor_delay_s=0.0, table_response_hz=math.inf)
    laws = {"library": run(ideal_rig), "yours": run(ideal_rig, HuntCrossleyContact(*yours))}
    rows, runs = [], {}
    for name in names:
        params = table1.with_(compensator=name)
        runs[f"library, {name}"] = library = run(params)
        check = run(params, HuntCrossleyContact(k_n_per_m, 1.0, 0.0))
        runs[f"yours, {name}"] = mine = run(params, HuntCrossleyContact(*yours))
        rows.append((name, library.metrics.cor, check.metrics.cor, mine.metrics.cor))
    print(
        f"Your Hunt-Crossley contact (n = {args.exponent:g}, d = {args.dissipation_s_per_m:g} "
        f"s/m, CoR {laws['yours'].metrics.cor:.4f} on an ideal rig) gives CoR "
        f"{runs['yours, none'].metrics.cor:.4f} uncompensated and "
        f"{runs['yours, SDMDC'].metrics.cor:.4f} with SDMDC in the Table 1 loop"
    )
    print(f"{'compensator':<12}{'library':>9}{'n=1, d=0':>10}{'yours':>9}")
    for row in rows:
        print(f"{row[0]:<12}{row[1]:>9.4f}{row[2]:>10.4f}{row[3]:>9.4f}")

    args.out.mkdir(parents=True, exist_ok=True)
    fig, axes = plt.subplots(1, 2, figsize=(9.6, 4.0))
    panels = (("p_act_m", "penetration p [m]", "the laws, ideal rig", laws),)
    panels += (("time_s", "time [s]", "in the Table 1 loop", runs),)
    for ax, (x_name, x_label, title, group) in zip(axes, panels, strict=True):
        for label, r in group.items():
            ax.plot(getattr(r, x_name), r.f_act_n, label=f"{label} (CoR {r.metrics.cor:.4f})")
        ax.set(xlabel=x_label, ylabel="contact force [N]", title=title)
        ax.legend(fontsize="small")
    axes[0].set_xlim(0.0, 1.1 * max(r.p_act_m.max() for r in laws.values()))
    axes[0].locator_params(axis="x", nbins=5)
    fig.tight_layout()
    fig.savefig(figure_path, dpi=120)
    print(f"wrote {figure_path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
