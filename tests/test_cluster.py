"""`scalesynth batch --scheduler` on a real dask cluster of separate OS processes on 127.0.0.1: a `dask scheduler`
and two `dask worker --no-nanny` processes, each started in its own directory tree (cwd, --local-directory, TMPDIR,
HOME), and the client (the CLI, another process) in a fourth tree holding OUT. No shared results directory: the
client must end up with every result although the workers never see OUT, a worker SIGKILLed in the middle of a
task loses nothing, and every task's Numba kernels use its worker's thread count.

Every wait is bounded and the fixture kills every process group it started, whatever happens.
"""

import copy
import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

from scalesynth.config import config_from_dict
from scalesynth.optimize import run
from scalesynth.rundir import staging_path

SEEDS = (1, 2, 3)
NTHREADS = {"w1": 1, "w2": 2}  # worker name -> --nthreads
PROCESS_TIMEOUT = 300  # seconds for one CLI batch (about 40 s on an idle 2-core machine)
RESULT_NAMES = {"pareto.csv", "population.csv", "history.csv", "manifest.json", "config.yaml", "report.md"}


def cluster_config(root: Path) -> dict:
    """configs/quick.yaml with chunks of about a second (grid 64, 48 designs, a checkpoint every 4 of 12
    generations), so that a SIGKILL seen while the scheduler reports a chunk processing lands inside it."""
    data = yaml.safe_load((root / "configs" / "quick.yaml").read_text())
    data.update(name="cluster", references={})
    data["grid"]["resolution"] = 64
    data["algorithm"].update(pop_size=48, n_gen=12, seed=SEEDS[0])
    data["output"] = {"dir": None, "checkpoint_every": 4}
    return data


def _wait_for(predicate, timeout: float, what: str, procs=()):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = predicate()
        if value:
            return value
        for p in procs:
            assert p.poll() is None, f"{what}: process {p.args[:4]} exited with {p.returncode}"
        time.sleep(0.05)
    raise AssertionError(f"timed out after {timeout} s waiting for {what}")


class Processes:
    """Processes started in their own sessions (process groups); stop() kills every group, always."""

    def __init__(self):
        self.procs: dict[str, subprocess.Popen] = {}

    def start(self, name: str, args: list[str], cwd: Path, env: dict[str, str]) -> subprocess.Popen:
        cwd.mkdir(parents=True, exist_ok=True)
        log = open(cwd / f"{name}.log", "wb")  # noqa: SIM115 - closed with the process
        p = subprocess.Popen(args, cwd=cwd, env=env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
        log.close()
        self.procs[name] = p
        return p

    def kill(self, name: str) -> None:
        p = self.procs[name]
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGKILL)
        p.wait(timeout=30)

    def stop(self) -> None:
        for p in self.procs.values():
            if p.poll() is None:
                try:
                    os.killpg(p.pid, signal.SIGTERM)
                except ProcessLookupError:
                    continue
        deadline = time.monotonic() + 10
        for p in self.procs.values():
            try:
                p.wait(timeout=max(0.1, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                pass
            if p.poll() is None:
                try:
                    os.killpg(p.pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
                p.wait(timeout=10)


def _env(tree: Path, numba_threads: int | None) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("NUMBA_NUM_THREADS", "DASK_"))}
    (tree / "tmp").mkdir(parents=True, exist_ok=True)
    env.update(TMPDIR=str(tree / "tmp"), HOME=str(tree), MPLBACKEND="Agg")
    if numba_threads is not None:
        env["NUMBA_NUM_THREADS"] = str(numba_threads)
    return env


def _dask(*args: str) -> list[str]:
    return [sys.executable, "-m", "dask", *args]


def start_worker(procs: Processes, base: Path, address: str, name: str, nthreads: int, numba_threads: int | None,
                 extra_env: dict[str, str] | None = None) -> None:
    tree = base / name
    env = {**_env(tree, numba_threads), **(extra_env or {})}
    procs.start(name, _dask("worker", address, "--name", name, "--nthreads", str(nthreads), "--no-nanny",
                            "--host", "127.0.0.1", "--no-dashboard", "--local-directory", str(tree / "local"),
                            "--death-timeout", "60"), tree, env)


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """A scheduler and two workers (w1: --nthreads 1 and no NUMBA_NUM_THREADS, so Numba's pool has all cores;
    w2: --nthreads 2 with NUMBA_NUM_THREADS=2, as docs/cluster.md advises), each in its own tree."""
    from dask.distributed import Client

    base = tmp_path_factory.mktemp("cluster")
    procs = Processes()
    try:
        sched_file = base / "scheduler" / "scheduler.json"
        args = _dask("scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard", "--scheduler-file",
                     str(sched_file))
        procs.start("scheduler", args, base / "scheduler", _env(base / "scheduler", 1))
        _wait_for(lambda: sched_file.is_file() and sched_file.stat().st_size > 0, 60, "the scheduler file",
                  procs.procs.values())
        address = json.loads(sched_file.read_text())["address"]
        assert address.startswith("tcp://127.0.0.1:")
        start_worker(procs, base, address, "w1", NTHREADS["w1"], None)
        start_worker(procs, base, address, "w2", NTHREADS["w2"], 2)
        with Client(address, timeout="30s", set_as_default=False) as client:
            client.wait_for_workers(2, timeout=60)
            yield {"base": base, "address": address, "procs": procs, "client": client}
    finally:
        procs.stop()


def _cli(args: list[str], cwd: Path) -> subprocess.Popen:
    cwd.mkdir(parents=True, exist_ok=True)
    scalesynth = Path(sys.executable).parent / "scalesynth"
    return subprocess.Popen([str(scalesynth), *args], cwd=cwd, env=_env(cwd, 1), stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)


def _finish(p: subprocess.Popen, timeout: float = PROCESS_TIMEOUT) -> tuple[int, str, str]:
    try:
        out, err = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        out, err = p.communicate(timeout=30)
        raise AssertionError(f"the batch did not finish in {timeout} s:\n{err[-3000:]}") from None
    return p.returncode, out, err


@pytest.fixture(scope="module")
def sequential(tmp_path_factory, root):
    """Each task run alone in this process: the reference bytes."""
    base = tmp_path_factory.mktemp("sequential")
    data = cluster_config(root)
    return {seed: run(config_from_dict(copy.deepcopy(data)), base / f"seed{seed}", seed=seed, plots=False).out_dir
            for seed in SEEDS}


@pytest.fixture(scope="module")
def killed_batch(cluster, root):
    """The batch, started from the client's tree with a relative --out; as soon as the scheduler reports a chunk
    that continues a task from a checkpoint (generation > 0) processing on a worker, that worker is SIGKILLed."""
    base, client, procs = cluster["base"], cluster["client"], cluster["procs"]
    tree = base / "client"
    tree.mkdir()
    (tree / "cluster.yaml").write_text(yaml.safe_dump(cluster_config(root)))
    args = ["batch", "cluster.yaml", "--seeds", str(len(SEEDS)), "--scheduler", cluster["address"],
            "--out", "results/batch", "--json"]
    p = _cli(args, tree)
    names = {a: w["name"] for a, w in client.scheduler_info(n_workers=-1)["workers"].items()}
    mid_task = re.compile(r"^scalesynth-cluster-seed\d+-gen([1-9]\d*)-")

    def chunk_in_progress():
        for address, keys in client.processing().items():
            if any(mid_task.match(str(k)) for k in keys):
                return address
        return None

    try:
        victim = _wait_for(chunk_in_progress, PROCESS_TIMEOUT, "a chunk continuing a task", [p])
        procs.kill(names[victim])
        killed_at = time.monotonic()
    finally:
        code, out, err = _finish(p)
    return {"tree": tree, "out": tree / "results" / "batch", "code": code, "stdout": out, "stderr": err,
            "victim": victim, "victim_name": names[victim], "names": names, "killed_at": killed_at, "args": args}


def _tasks(summary):
    return {t["seed"]: t for t in summary["tasks"]}


def test_the_batch_survives_a_killed_worker_and_the_client_has_every_result(killed_batch, sequential):
    kb = killed_batch
    assert kb["code"] == 0, kb["stderr"][-3000:]
    out = kb["out"]
    summary = json.loads((out / "batch.json").read_text())
    assert json.loads(kb["stdout"]) == summary
    assert summary["out"] == str(out) and summary["n_finished"] == len(SEEDS) and summary["n_failed"] == 0
    tasks = _tasks(summary)
    for seed in SEEDS:
        t, d = tasks[seed], out / "cluster" / f"seed{seed}"
        assert t["status"] == "finished" and Path(t["results"]) == d, t
        assert {Path(f).name for f in t["files"]} == RESULT_NAMES - {"report.md"}
        assert all(Path(f).is_file() and Path(f).parent == d for f in t["files"])
        assert t["checkpoint"] is None and not (d / "checkpoint.pkl").exists() and not staging_path(d).exists()
        # the front of a task whose worker died mid-task is byte-identical to an uninterrupted sequential run
        for f in ("pareto.csv", "population.csv"):
            assert (d / f).read_bytes() == (sequential[seed] / f).read_bytes(), (seed, f)
        assert t["chunks"] >= 3 and t["worker"] == t["workers"][-1]["address"]
        assert sum(w["chunks"] for w in t["workers"]) == t["chunks"]
    # the chunk that was running on the killed worker was run again elsewhere: one retry, recorded with the worker
    retried = [t for t in tasks.values() if t["retries"]]
    assert [t["lost_workers"] for t in retried] == [[kb["victim"]]], [t["lost_workers"] for t in tasks.values()]
    survivor = next(a for a, n in kb["names"].items() if a != kb["victim"])
    assert retried[0]["worker"] == survivor
    assert f"worker {kb['victim']} lost while running generations after" in kb["stderr"]
    assert set(summary["workers"]) == set(kb["names"])
    assert (out / "cluster" / "combined_pareto.csv").is_file()
    assert (out / "cluster" / "hypervolume_by_seed.png").is_file()


def test_every_task_used_its_workers_thread_count(killed_batch):
    """Every chunk's kernels used its worker's --nthreads: 1 on w1 although its Numba pool has every core (no
    NUMBA_NUM_THREADS there), 2 on w2; and each manifest records the count of the worker that finished the task.
    Both workers ran chunks (the first two chunks go to the two idle workers; the victim finished one before the
    kill)."""
    out = killed_batch["out"]
    tasks = _tasks(json.loads((out / "batch.json").read_text()))
    seen = set()
    for seed in SEEDS:
        t = tasks[seed]
        for w in t["workers"]:
            assert w["nthreads"] == w["numba_threads"] == NTHREADS[w["name"]], t["workers"]
            seen.add(w["name"])
        manifest = json.loads((out / "cluster" / f"seed{seed}" / "manifest.json").read_text())
        assert manifest["machine"]["numba_threads"] == t["numba_threads"] == NTHREADS[t["worker_name"]], t
    assert seen == set(NTHREADS)


def test_workers_wrote_nothing_outside_their_scratch(killed_batch, cluster):
    """OUT is only in the client's tree and only the client wrote there; the surviving worker's tree holds no
    results and no checkpoint (its scratch directories are removed after each chunk), and no worker made the
    relative --out inside its own tree."""
    base = cluster["base"]
    out = killed_batch["out"]
    expected = {"batch.json", "cluster/combined_pareto.csv", "cluster/hypervolume_by_seed.png"} | {
        f"cluster/seed{s}/{f}" for s in SEEDS for f in RESULT_NAMES - {"report.md"}
    }
    assert {str(p.relative_to(out)) for p in out.rglob("*") if p.is_file()} == expected
    for name in NTHREADS:
        tree = base / name
        assert not (tree / "results").exists()
        leftovers = [p for p in tree.rglob("*") if p.is_file() and (p.name in RESULT_NAMES or p.suffix == ".pkl")]
        if name != killed_batch["victim_name"]:
            assert leftovers == [], leftovers
            assert not list(tree.rglob("scalesynth-chunk-*"))
        else:  # at most the scratch of the chunk it was killed in (its run staged there: scalesynth.rundir)
            chunks = set(tree.rglob("scalesynth-chunk-*"))
            assert len(chunks) <= 1 and all(chunks & set(p.parents) for p in leftovers), leftovers


def test_a_rerun_skips_every_finished_task_wherever_it_ran(killed_batch):
    out = killed_batch["out"]
    before = {p: (p.stat().st_mtime_ns, p.read_bytes()) for p in out.glob("cluster/seed*/*")}
    code, stdout, stderr = _finish(_cli(killed_batch["args"], killed_batch["tree"]))
    assert code == 0, stderr[-3000:]
    tasks = _tasks(json.loads(stdout))
    assert [tasks[s]["status"] for s in SEEDS] == ["skipped"] * len(SEEDS)
    assert all(tasks[s]["chunks"] == 0 and tasks[s]["worker"] is None for s in SEEDS)
    assert {p: (p.stat().st_mtime_ns, p.read_bytes()) for p in out.glob("cluster/seed*/*")} == before


def test_a_worker_with_another_scalesynth_version_is_named_and_nothing_runs(killed_batch, cluster, tmp_path):
    """A third worker whose installed scalesynth metadata says 9.9.9 (a dist-info first on its PYTHONPATH): the
    batch stops before submitting anything, exit 1, one line naming that worker and the versions."""
    from importlib.metadata import version

    fake = tmp_path / "site"
    info = fake / "scalesynth-9.9.9.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: scalesynth\nVersion: 9.9.9\n")
    start_worker(cluster["procs"], cluster["base"], cluster["address"], "w3", 1, 1, {"PYTHONPATH": str(fake)})
    client = cluster["client"]
    try:
        client.wait_for_workers(2, timeout=60)  # the survivor and w3
        w3 = _wait_for(lambda: [a for a, w in client.scheduler_info(n_workers=-1)["workers"].items()
                                if w["name"] == "w3"], 60, "w3 to register")[0]
        tree = tmp_path / "client"
        (tree / "results").mkdir(parents=True)
        (tree / "cluster.yaml").write_text((killed_batch["tree"] / "cluster.yaml").read_text())
        sched_file = cluster["base"] / "scheduler" / "scheduler.json"  # the address, as jobqueue users pass it
        code, stdout, stderr = _finish(_cli(["batch", "cluster.yaml", "--scheduler-file", str(sched_file),
                                             "--out", "results/b"], tree), 120)
        assert code == 1 and stdout == ""
        assert stderr.strip().splitlines() == [
            f"error: worker {w3} (w3): scalesynth 9.9.9 (client {version('scalesynth')})"
        ]
        assert not (tree / "results" / "b").exists()
    finally:
        cluster["procs"].kill("w3")
