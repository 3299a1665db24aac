"""A campaign on a real Dask cluster started from the command line: the same
file as on a local cluster and on one worker; a lost worker costs nothing."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from hybridtable.cli import main

#: A real `dask scheduler` and two `dask worker` processes (make test runs it; `-m "not cluster"` leaves it out).
pytestmark = pytest.mark.cluster

DASK = Path(sys.executable).parent / "dask"

SPEC = """
name = "cluster_check"
seed = 11
compensators = ["none", "SDC", "MDC", "SDMDC"]
metrics = ["cor", "peak_force_n", "contact_duration_s", "energy_gain_j"]

[base]
contact_frequency_hz = 2.0

[monte_carlo]
samples = 15

[monte_carlo.draw]
contact_stiffness_n_per_m = {distribution = "log_uniform", low = 1e4, high = 1e6}
sensor_delay_s = {distribution = "uniform", low = 0.001, high = 0.03}
initial_velocity_m_per_s = {distribution = "normal", mean = 0.1, std = 0.03, low = 0.02, high = 0.3}
"""


def _without_timing(path: Path):
    table = pq.read_table(path)
    return table.drop_columns(["seconds"])


def _start(args: list[str], log: Path) -> subprocess.Popen:
    return subprocess.Popen(
        [str(DASK), *args],
        stdout=subprocess.DEVNULL,
        stderr=open(log, "w"),  # noqa: SIM115 (closed with the process)
        start_new_session=True,
    )


def _worker(scheduler_file: Path, name: str, log: Path) -> subprocess.Popen:
    """A ``dask worker`` process of one single-threaded worker."""
    args = ["worker", "--scheduler-file", str(scheduler_file), "--nworkers", "1"]
    return _start([*args, "--nthreads", "1", "--no-dashboard", "--name", name], log)


def _stop(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        os.killpg(proc.pid, signal.SIGTERM)
        try:
            proc.wait(20)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(10)


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """A ``dask scheduler`` and two ``dask worker`` processes on localhost."""
    folder = tmp_path_factory.mktemp("cluster")
    file = folder / "scheduler.json"
    procs = [
        _start(
            [
                "scheduler",
                "--host",
                "127.0.0.1",
                "--port",
                "0",
                "--no-dashboard",
                "--scheduler-file",
                str(file),
            ],
            folder / "scheduler.log",
        )
    ]
    try:
        deadline = time.monotonic() + 60
        while not file.exists() and time.monotonic() < deadline:
            time.sleep(0.2)
        assert file.exists(), (folder / "scheduler.log").read_text()
        address = json.loads(file.read_text())["address"]
        for i in range(2):
            procs.append(_worker(file, f"w{i}", folder / f"worker{i}.log"))
        yield {"address": address, "file": file, "folder": folder}
    finally:
        for p in reversed(procs):
            _stop(p)


def test_the_scheduler_a_local_cluster_and_one_worker_write_the_same_file(
    cluster, tmp_path, capsys
):
    spec = tmp_path / "spec.toml"
    spec.write_text(SPEC)
    remote, local, single = (tmp_path / f"{n}.parquet" for n in ("remote", "local", "single"))
    code = main(
        [
            "sweep",
            str(spec),
            "--out",
            str(remote),
            "--scheduler",
            cluster["address"],
            "--workers",
            "2",
            "--no-progress",
        ]
    )
    assert code == 0, capsys.readouterr().err
    err = capsys.readouterr().err
    assert "2 Dask workers" in err
    assert main(["sweep", str(spec), "--out", str(local), "--workers", "2", "--no-progress"]) == 0
    assert main(["sweep", str(spec), "--out", str(single), "--workers", "1", "--no-progress"]) == 0
    a, b, c = (_without_timing(p) for p in (remote, local, single))
    assert a.num_rows == 60
    assert a.column("run").to_pylist() == list(range(60))
    assert repr(a.to_pylist()) == repr(b.to_pylist()) == repr(c.to_pylist())
    # the metadata too (the spec and its fingerprint), not only the rows
    assert pq.read_schema(remote).metadata == pq.read_schema(local).metadata
    status = a.column("status").to_pylist()
    assert status.count("ok") == 60
    cor = a.column("cor").to_pylist()
    comps = a.column("compensator").to_pylist()
    # physics: without compensation the delay always pumps energy in
    assert all(c > 1.0 for c, k in zip(cor, comps, strict=True) if k == "none")


def _worker_named(client, name: str) -> str | None:
    for address, info in client.scheduler_info()["workers"].items():
        if info.get("name") == name:
            return address
    return None


def test_a_lost_worker_costs_only_its_runs(cluster, tmp_path):
    """Kill a third worker while it holds tasks: the scheduler gives them to the
    others and the file is the same as an undisturbed run's."""
    from distributed import Client

    spec = tmp_path / "spec.toml"
    text = SPEC.replace('name = "cluster_check"', 'name = "lost_worker"\nengine = "diagram"')
    spec.write_text(text.replace("samples = 15", "samples = 12"))
    extra = _worker(cluster["file"], "doomed", tmp_path / "doomed.log")
    out = tmp_path / "lost.parquet"
    client = Client(cluster["address"], timeout="30s")
    try:
        client.wait_for_workers(3, timeout=60)
        doomed = _worker_named(client, "doomed")
        campaign = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "hybridtable.cli",
                "sweep",
                str(spec),
                "--out",
                str(out),
                "--scheduler",
                cluster["address"],
                "--workers",
                "3",
                "--no-progress",
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        held = []
        deadline = time.monotonic() + 120
        while not held and time.monotonic() < deadline and campaign.poll() is None:
            held = list(client.processing().get(doomed, ()))
            time.sleep(0.05)
        assert held, "the third worker never got a task"
        os.killpg(extra.pid, signal.SIGKILL)
        stdout, stderr = campaign.communicate(timeout=600)
    finally:
        client.close()
        _stop(extra)
    assert campaign.returncode == 0, stderr
    table = _without_timing(out)
    assert table.num_rows == 48
    assert table.column("status").to_pylist().count("ok") == 48
    reference = tmp_path / "reference.parquet"
    assert (
        main(
            [
                "sweep",
                str(spec),
                "--out",
                str(reference),
                "--scheduler",
                cluster["address"],
                "--no-progress",
            ]
        )
        == 0
    )
    assert repr(table.to_pylist()) == repr(_without_timing(reference).to_pylist())


def test_no_scheduler_at_the_address_is_one_line(tmp_path, capsys):
    spec = tmp_path / "spec.toml"
    spec.write_text(SPEC)
    out = tmp_path / "x.parquet"
    code = main(["sweep", str(spec), "--out", str(out), "--scheduler", "tcp://127.0.0.1:9"])
    err = capsys.readouterr().err
    assert code == 2
    assert "no Dask scheduler answers" in err and err.count("\n") == 1
    assert not out.exists()


ENVELOPE = Path(__file__).resolve().parents[2] / "examples" / "sweeps" / "docking_envelope.toml"


def test_the_shipped_6dof_campaign_gives_the_same_file_on_the_scheduler_and_one_worker(
    cluster, tmp_path, capsys
):
    """The shipped docking envelope, cut to three draws (nine 6-DoF runs), on
    the scheduler's two workers and on one local worker: the same rows and
    metadata."""
    import tomllib

    raw = tomllib.loads(ENVELOPE.read_text())
    text = ENVELOPE.read_text().replace("samples = 500", "samples = 3")
    text = text.replace(
        f'scenario = "{raw["scenario"]}"', f'scenario = "{ENVELOPE.parent / raw["scenario"]}"'
    )
    spec = tmp_path / "envelope.toml"
    spec.write_text(text)
    remote, single = tmp_path / "remote.parquet", tmp_path / "single.parquet"
    args = ["sweep", str(spec), "--no-progress", "--out"]
    assert main([*args, str(remote), "--scheduler", cluster["address"]]) == 0, capsys.readouterr()
    assert main([*args, str(single), "--workers", "1"]) == 0, capsys.readouterr()
    a, b = _without_timing(remote), _without_timing(single)
    assert a.num_rows == 9
    assert repr(a.to_pylist()) == repr(b.to_pylist())
    assert pq.read_schema(remote).metadata == pq.read_schema(single).metadata
    rows = a.to_pylist()
    assert [r["status"] for r in rows] == ["ok"] * 9
    for r in rows:  # the delay pumps energy in; the identifier takes it back out
        if r["compensator"] == "none":
            assert r["energy_ratio"] > 1.05
        if r["compensator"] == "sdmdc-online":
            assert abs(r["energy_ratio"] - 1.0) < 0.01
