"""The 6-DoF docking loop of a scenario file, once per compensator.

1. `load_scenario` reads a scenario (`examples/six_dof/*.toml`) into
   `DockingLoopParams`; keyword overrides set the compensator and the rate.
2. `add_docking_loop` adds the rigid spacecraft, the table back-end with
   Drake's compliant contact of the docking ring, the F/T sensor's delay and
   the wrench compensator to our own DiagramBuilder.
3. `simulate6(params, loop=loop)` runs the built loop through the contact.
4. Prints a verdict, then the normal CoR, energy ratio, peak force and peak
   moment of each run; writes `--out`/docking.png (the port's normal velocity
   and the contact moment against time) and `--out`/metrics.csv.
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from pydrake.systems.framework import DiagramBuilder

import hybridtable
from hybridtable import six_dof
from hybridtable.six_dof.scenario import load_scenario

SCENARIO = Path(__file__).resolve().parents[1] / "examples" / "six_dof" / "offset.toml"


def dock(scenario: Path, compensator: str, sample_rate_hz: float | None):
    """One docking run of ``scenario`` in our own diagram."""
    rate = {} if sample_rate_hz is None else {"sample_rate_hz": sample_rate_hz}
    params = load_scenario(scenario, compensator=compensator, **rate)
    builder = DiagramBuilder()
    loop = six_dof.add_docking_loop(builder, params)
    loop.diagram = builder.Build()  # simulate6 and the loop's initial state use it
    return six_dof.simulate6(loop.params, loop=loop)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    parser.add_argument("--scenario", type=Path, default=SCENARIO, help="6-DoF scenario (TOML)")
    parser.add_argument("--rate-hz", type=float, help="rig rate [Hz]; None: the scenario's")
    parser.add_argument(
        "--quick", action="store_true", help="only none and SDMDC, at 500 Hz (not --rate-hz)"
    )
    parser.add_argument(
        "--out", type=Path, default=Path("out/diagrams/docking_6dof"), help="output folder"
    )
    parser.add_argument("--force", action="store_true", help="replace existing outputs")
    args = parser.parse_args(argv)
    figure_path, csv_path = args.out / "docking.png", args.out / "metrics.csv"
    for path in (figure_path, csv_path):
        if path.exists() and not args.force:
            parser.exit(2, f"refusing to replace {path} (give --force)\n")
    names = ("none", "SDMDC") if args.quick else hybridtable.COMPENSATORS
    rate_hz = 500.0 if args.quick else args.rate_hz
    try:
        load_scenario(args.scenario, **({} if rate_hz is None else {"sample_rate_hz": rate_hz}))
    except hybridtable.ParameterError as err:  # SpecError: one line naming the file and key
        parser.error(str(err))

    runs = {name: dock(args.scenario, name, rate_hz) for name in names}
    m = {name: run.metrics for name, run in runs.items()}
    rate_hz = runs[names[0]].params.sample_rate_hz
    print(
        f"On {args.scenario.name} at {rate_hz:g} Hz SDMDC gives a normal CoR of "
        f"{m['SDMDC'].cor_normal:.4f} and an energy ratio of {m['SDMDC'].energy_ratio:.4f} "
        f"(none: {m['none'].cor_normal:.4f}, {m['none'].energy_ratio:.4f})"
    )
    header = ("compensator", "cor_normal", "energy_ratio", "peak_force_n", "peak_moment_n_m")
    print(f"{header[0]:<12}{'CoR':>8}{'energy':>8}{'peak force [N]':>16}{'moment [N m]':>14}")
    rows = [
        (n, m[n].cor_normal, m[n].energy_ratio, m[n].peak_force_n, m[n].peak_moment_n_m)
        for n in names
    ]
    for name, cor, energy, force_n, moment_n_m in rows:
        print(f"{name:<12}{cor:>8.4f}{energy:>8.4f}{force_n:>16.1f}{moment_n_m:>14.1f}")
    for name in names:
        if m[name].spin_note:
            print(f"{name}: {m[name].spin_note}")

    args.out.mkdir(parents=True, exist_ok=True)
    with open(csv_path, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(header)
        writer.writerows(rows)
    fig, (vel, mom) = plt.subplots(2, 1, sharex=True, figsize=(6.4, 5.6))
    for name, run in runs.items():
        vel.plot(run.time_s, run.port_velocity_m_per_s[:, 2], label=name)
        mom.plot(run.time_s, np.linalg.norm(run.log["contact_wrench"][:, :3], axis=1))
    vel.set_ylabel("port velocity along the axis [m/s]")
    vel.set_title(f"{args.scenario.name}, {rate_hz:g} Hz rig")
    vel.legend()
    mom.set_xlabel("time [s]")
    mom.set_ylabel("contact moment [N m]")
    fig.tight_layout()
    fig.savefig(figure_path, dpi=120)
    print(f"wrote {figure_path} and {csv_path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
