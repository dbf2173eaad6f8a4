"""Faults on a Dask cluster: a worker killed mid-cell, the scheduler killed, a worker without ogcp.

The cluster is real: a ``dask scheduler`` and ``dask worker`` processes (nannies restart a killed
worker), and the suite runs as ``ogcp suite`` in its own process, as a user runs it.
"""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from ogcp.benchmarks.suite.parse import load_suite
from ogcp.benchmarks.suite.runner import SuiteRunner
from ogcp.benchmarks.suite.store import ResultStore
from ogcp.planner.infra import OgcpError

distributed = pytest.importorskip("distributed")

SUITE = """
schema_version = 1
name = "faults"
objects = ["box"]
contacts = 60
contact_seeds = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9]
m = [4]

[[methods]]
method = "dijkstra"
"""
CELLS = 10  # of about 0.5 s each: a fault lands while most are still to run
DASK = Path(sys.executable).with_name("dask")


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


@contextmanager
def _cluster(workers: int = 1, env: dict[str, str] | None = None) -> Iterator[tuple[str, subprocess.Popen]]:
    """A scheduler and ``workers`` single-threaded workers (each under a nanny) on a free port."""
    port = _free_port()
    address = f"127.0.0.1:{port}"
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}
    scheduler = subprocess.Popen(
        [str(DASK), "scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"], **quiet
    )
    worker = subprocess.Popen(
        [str(DASK), "worker", address, "--nworkers", str(workers), "--nthreads", "1", "--no-dashboard"],
        env=env,
        **quiet,
    )
    try:
        with distributed.Client(address, timeout="60s") as client:
            client.wait_for_workers(workers, timeout=120)
        yield address, scheduler
    finally:
        for process in (worker, scheduler):
            process.kill()
            process.wait(timeout=60)


def _suite(tmp_path: Path) -> Path:
    path = tmp_path / "faults.toml"
    path.write_text(SUITE)
    return path


def _ogcp_suite(suite: Path, out: Path, address: str, *extra: str) -> subprocess.Popen[str]:
    command = [sys.executable, "-m", "ogcp.benchmarks.cli", "suite", str(suite), "--out", str(out)]
    command += ["--backend", "dask", "--address", address, *extra]
    return subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _records(out: Path) -> dict[str, float]:
    records = ResultStore(out).read().records
    ids = [r["id"] for r in records]
    assert len(ids) == len(set(ids)), "a cell was recorded twice"
    return {r["id"]: r["plan"]["q1"] for r in records}


def _wait_for_records(out: Path, count: int, run: subprocess.Popen[str], timeout: float = 300) -> None:
    path = out / "results.jsonl"
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and run.poll() is None:
        if path.exists() and len(path.read_text(encoding="utf-8").splitlines()) >= count:
            return
        time.sleep(0.1)
    raise AssertionError(f"fewer than {count} records in {path} before the run ended")


@pytest.fixture(scope="module")
def serial(tmp_path_factory: pytest.TempPathFactory) -> dict[str, float]:
    folder = tmp_path_factory.mktemp("serial")
    out = folder / "out"
    SuiteRunner(load_suite(_suite(folder)), out).run()
    return _records(out)


def test_a_killed_scheduler_ends_the_suite_in_one_line_and_resume_finishes_it(tmp_path, serial):
    suite, out = _suite(tmp_path), tmp_path / "out"
    with _cluster() as (address, scheduler):
        run = _ogcp_suite(suite, out, address)
        _wait_for_records(out, 1, run)
        scheduler.send_signal(signal.SIGKILL)
        _, err = run.communicate(timeout=180)
    assert run.returncode == 2, (len(_records(out)), err[-3000:])
    lines = [line for line in err.splitlines() if line.startswith("ogcp: error")]
    assert len(lines) == 1 and "the Dask scheduler" in lines[0] and "--resume" in lines[0], err
    assert "Traceback" not in err
    kept = _records(out)
    assert 1 <= len(kept) < CELLS and all(serial[k] == v for k, v in kept.items())
    with _cluster() as (address, _):
        again = _ogcp_suite(suite, out, address, "--resume")
        _, err = again.communicate(timeout=300)
    assert again.returncode == 0, err
    assert _records(out) == serial


def test_a_worker_killed_during_a_cell_has_the_cell_run_again(tmp_path, serial):
    suite, out = _suite(tmp_path), tmp_path / "out"
    with _cluster(workers=2) as (address, _):
        run = _ogcp_suite(suite, out, address)
        _wait_for_records(out, 1, run)
        with distributed.Client(address, timeout="30s") as client:
            busy = [w for w, tasks in client.processing().items() if tasks]
            assert busy, "no worker was running a cell"
            pids = client.run(os.getpid, workers=busy[:1])
        os.kill(next(iter(pids.values())), signal.SIGKILL)
        _, err = run.communicate(timeout=300)
    assert run.returncode == 0, err
    assert _records(out) == serial  # every cell once, as in a serial run


def test_a_worker_that_cannot_import_ogcp_is_named(tmp_path):
    shadow = tmp_path / "shadow" / "ogcp"
    shadow.mkdir(parents=True)
    (shadow / "__init__.py").write_text('raise ImportError("no ogcp in this environment")\n')
    env = {**os.environ, "PYTHONPATH": str(shadow.parent)}
    refused = pytest.raises(OgcpError, match=r"Dask worker tcp://\S+ cannot import ogcp\.benchmarks\.suite\.runner")
    with _cluster(env=env) as (address, _), refused:
        SuiteRunner(load_suite(_suite(tmp_path)), tmp_path / "out", backend="dask", address=address).run()
    results = tmp_path / "out" / "results.jsonl"
    assert not results.exists() or not results.read_text(encoding="utf-8").strip()  # no cell ran


def test_exhaustive_search_keeps_its_chunks_when_the_scheduler_dies_and_the_rerun_finishes(tmp_path):
    checkpoint = tmp_path / "chunks"
    plan = [sys.executable, "-m", "ogcp.benchmarks.cli", "plan", "box", "-n", "40", "-m", "4"]
    plan += ["--method", "es", "--chunk", "2000", "--json"]
    command = [*plan, "--checkpoint", str(checkpoint)]
    serial = subprocess.run(plan, capture_output=True, text=True, timeout=600, check=False)
    assert serial.returncode == 0, serial.stderr
    with _cluster() as (address, scheduler):
        run = subprocess.Popen(
            [*command, "--backend", "dask", "--address", address],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        deadline = time.monotonic() + 300
        while not list(checkpoint.glob("chunk_*.json")) and run.poll() is None and time.monotonic() < deadline:
            time.sleep(0.05)
        scheduler.send_signal(signal.SIGKILL)
        _, err = run.communicate(timeout=180)
    assert run.returncode == 2, err
    assert err.strip().splitlines()[-1].startswith("ogcp: error: the Dask scheduler") and "Traceback" not in err
    kept = len(list(checkpoint.glob("chunk_*.json")))
    assert 1 <= kept < 46  # C(40, 4) = 91,390 grasps in 46 chunks
    with _cluster() as (address, _):
        again = subprocess.run(
            [*command, "--backend", "dask", "--address", address],
            capture_output=True,
            text=True,
            timeout=600,
            check=False,
        )
    assert again.returncode == 0, again.stderr
    first, second = json.loads(serial.stdout), json.loads(again.stdout)
    assert second["grasp"] == first["grasp"] and second["q1"] == first["q1"]
    assert second["stats"]["resumed_chunks"] == kept
