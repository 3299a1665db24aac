"""How the audits of a rig computer's compensation law read a log whose
readings carry noise the computer did not see (a logger of its own): the
false findings on a computer that did what its JSON says, and how often a
wrong lead, MDC stiffness or dead band is found, over seeds.

Records come from the independent generators (``tests/generators``: rigsim
for 1-D, rig6 for 6-DoF), their logger's noise added after their loop
(1-D: 2 N and 2 um; 6-DoF: 2 N, 0.5 N m, 2 um). Prints one line a case:
findings / seeds, and the JSON's law's misfit in noise levels (median and
largest); the threshold is ``measurement.audit_fit.NOISE_LEVELS``.

    python benchmarks/audit_noise.py --seeds 20
"""

from __future__ import annotations

import argparse
import copy
import pathlib
import sys
import tempfile

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

from hybridtable.measurement.audit import audit_runs  # noqa: E402
from hybridtable.measurement.run_reader import read_run  # noqa: E402
from hybridtable.six_dof.audit_law6 import audit_compensation6  # noqa: E402
from hybridtable.six_dof.run6 import read_runs6  # noqa: E402
from tests.generators.rigsim import NOMINAL, simulate_record, write_run  # noqa: E402
from tests.generators.run6_logs import generate_run6, scenario, write_run6  # noqa: E402


def one_d(folder: pathlib.Path, used: dict, seed: int) -> tuple[bool, float]:
    cols = simulate_record(
        dict(NOMINAL, **used), seed=seed, duration_s=0.5, noise_f_n=0.0, noise_p_m=0.0
    )
    rng = np.random.default_rng(seed)
    cols["f_mea_n"] = cols["f_mea_n"] + 2.0 * rng.standard_normal(len(cols["f_mea_n"]))
    cols["p_act_m"] = cols["p_act_m"] + 2e-6 * rng.standard_normal(len(cols["p_act_m"]))
    said = dict(NOMINAL, run_id=f"s{seed}")
    audit = audit_runs([read_run(write_run(folder, f"s{seed}", said, cols))])
    return bool(audit.findings), audit.estimates[0].compensation_noise_levels


def six_dof(folder: pathlib.Path, used: dict, seed: int) -> tuple[bool, float]:
    told = scenario(compensator={"name": "SDMDC"})
    run_as = copy.deepcopy(told)
    run_as["compensator"].update(used)
    rows = generate_run6(
        run_as, seed=seed, force_noise_n=2.0, moment_noise_n_m=0.5, position_noise_m=2e-6
    )
    write_run6(folder, f"s{seed}", told, rows)
    audit = audit_compensation6(read_runs6([folder / f"s{seed}.csv"]))
    return bool(audit.findings), audit.noise_levels


CASES = (
    ("1-D", "its own computer", one_d, {}),
    ("1-D", "lead 0.5 ms off", one_d, {"lead_time_s": 0.0035}),
    ("1-D", "lead 1 ms off", one_d, {"lead_time_s": 0.003}),
    ("1-D", "MDC stiffness 10 % off", one_d, {"contact_stiffness_n_per_m": 66000.0}),
    ("1-D", "dead band 30 N, JSON 6 N", one_d, {"force_deadband_n": 30.0}),
    ("6-DoF", "its own computer", six_dof, {}),
    ("6-DoF", "lead 0.5 ms off", six_dof, {"lead_time_s": 0.0045}),
    ("6-DoF", "lead 1 ms off", six_dof, {"lead_time_s": 0.004}),
    ("6-DoF", "dead band 20 N, JSON 0", six_dof, {"force_deadband_n": 20.0}),
)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=20, help="seeds a case (default 20)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        for k, (loop, case, make, used) in enumerate(CASES):
            folder = pathlib.Path(tmp) / str(k)
            folder.mkdir()
            found, levels = zip(*(make(folder, used, s) for s in range(args.seeds)), strict=True)
            lv = np.array(levels, dtype=float)
            print(
                f"{loop:6s} {case:28s} found {sum(found):3d} / {args.seeds}   levels median "
                f"{np.nanmedian(lv):.3g}, largest {np.nanmax(lv):.3g}",
                flush=True,
            )


if __name__ == "__main__":
    main()
