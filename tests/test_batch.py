"""`scalesynth batch` on a real dask LocalCluster (two worker processes): results equal sequential runs byte for
byte, failing tasks do not stop the others (exit 1), re-running skips finished tasks and resumes unfinished ones.

The main tests share one cluster (module fixture, passed as --scheduler, which also tests an existing cluster);
one test starts the embedded cluster that `batch` creates without --scheduler.
"""

import copy
import json
import logging
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml
from typer.testing import CliRunner

from fake_dask import InlineClient, use_inline_dask
from scalesynth.batch import combined_front, format_table, local_cluster_shape, nondominated_mask, run_batch
from scalesynth.cli import app
from scalesynth.config import config_from_dict
from scalesynth.errors import RunError
from scalesynth.optimize import run
from scalesynth.rundir import staging_path

from conftest import SMALL as SMALL_RUN

SMALL = {**SMALL_RUN, "name": "alpha"}
ALPHA = SMALL
# a maximised and a minimised objective, so the combined front's minimisation form is exercised
BETA = {
    **SMALL,
    "name": "beta",
    "objectives": [{"metric": "band_volume", "band": 2}, {"metric": "fci", "sense": "min"}],
    "algorithm": {"pop_size": 16, "n_gen": 5, "seed": 11},
}
NOBOUNDS = {**SMALL, "name": "nobounds", "bounds": {}}  # valid config, but its run raises (nothing to optimise)
BLOCKED = {**SMALL, "name": "blocked"}  # OUT/blocked will be a regular file: its directories cannot be made
SEEDS = {"alpha": [3, 4], "beta": [11, 12]}


def _write(path: Path, data: dict) -> Path:
    path.write_text(yaml.safe_dump(copy.deepcopy(data)))
    return path


@pytest.fixture(scope="module")
def cluster():
    from dask.distributed import LocalCluster

    with LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        dashboard_address=":0",
        scheduler_kwargs={"dashboard": False},
        silence_logs=logging.ERROR,
        env={"NUMBA_NUM_THREADS": "1"},
    ) as c:
        yield c.scheduler_address


@pytest.fixture(scope="module")
def sequential(tmp_path_factory):
    """Each task run on its own, in this process (default Numba threads): the reference bytes."""
    base = tmp_path_factory.mktemp("sequential")
    out = {}
    for data in (ALPHA, BETA):
        for seed in SEEDS[data["name"]]:
            res = run(config_from_dict(copy.deepcopy(data)), base / data["name"] / f"seed{seed}", seed=seed,
                      plots=False)
            out[(data["name"], seed)] = res.out_dir
    return out


@pytest.fixture(scope="module")
def first_batch(tmp_path_factory, cluster):
    """A batch of 4 configs x 2 seeds: alpha seed 4 left unfinished beforehand (a checkpoint after 2
    generations), nobounds fails in its run, blocked cannot create its directories."""
    tmp = tmp_path_factory.mktemp("batch")
    paths = [_write(tmp / f"{d['name']}.yaml", d) for d in (ALPHA, BETA, NOBOUNDS, BLOCKED)]
    out = tmp / "out"
    out.mkdir()
    (out / "blocked").write_text("a file where the batch wants a directory\n")
    with pytest.raises(RunError):
        run(config_from_dict(copy.deepcopy(ALPHA)), out / "alpha" / "seed4", seed=4, plots=False, stop_after=2)
    assert (staging_path(out / "alpha" / "seed4") / "checkpoint.pkl").exists()
    args = ["batch", *map(str, paths), "--seeds", "2", "--out", str(out), "--scheduler", cluster]
    result = CliRunner().invoke(app, args)
    return {"out": out, "args": args, "result": result, "summary": json.loads((out / "batch.json").read_text())}


def _tasks(summary):
    return {(t["config"], t["seed"]): t for t in summary["tasks"]}


def test_failing_tasks_do_not_stop_the_others_and_exit_1(first_batch):
    r, summary = first_batch["result"], first_batch["summary"]
    assert r.exit_code == 1, r.output
    tasks = _tasks(summary)
    assert len(tasks) == 8 and summary["n_failed"] == 4 and summary["n_finished"] == 4
    for key in [("alpha", 3), ("alpha", 4), ("beta", 11), ("beta", 12)]:
        t = tasks[key]
        assert t["status"] == "finished" and t["error"] is None, t
        assert t["hypervolume"] > 0 and t["pareto_size"] >= 1 and t["wall_seconds"] > 0
        assert Path(t["results"]) == first_batch["out"] / key[0] / f"seed{key[1]}"
    for seed in (3, 4):
        t = tasks[("nobounds", seed)]
        assert t["status"] == "failed" and t["hypervolume"] is None
        assert t["error"] == "bounds: at least one design variable needs bounds to optimise"
        t = tasks[("blocked", seed)]
        assert t["status"] == "failed" and "cannot create output directory" in t["error"]
        assert "\n" not in t["error"]
    # the table lists every task with its status; the failures' errors are on their rows
    lines = r.output.splitlines()
    assert "4 of 8 tasks failed" in r.output
    assert any(ln.startswith("nobounds") and "failed" in ln and "bounds: at least one" in ln for ln in lines)
    assert sum(" finished " in ln for ln in lines if ln.startswith(("alpha", "beta"))) == 4
    assert summary["combined"]["nobounds"]["seeds"] == [] and summary["combined"]["nobounds"]["failed_seeds"] == [3, 4]


def test_batch_results_equal_sequential_runs_byte_for_byte(first_batch, sequential):
    """Determinism under the batch runner: worker processes with one Numba thread each reproduce the sequential
    runs exactly, including alpha seed 4, which the batch resumed from a checkpoint."""
    out = first_batch["out"]
    for (name, seed), ref_dir in sequential.items():
        for f in ("pareto.csv", "population.csv"):
            assert (out / name / f"seed{seed}" / f).read_bytes() == (ref_dir / f).read_bytes(), (name, seed, f)
        h_batch = pd.read_csv(out / name / f"seed{seed}" / "history.csv")
        h_ref = pd.read_csv(ref_dir / "history.csv")
        pd.testing.assert_frame_equal(h_batch.drop(columns="seconds"), h_ref.drop(columns="seconds"))
        assert not (out / name / f"seed{seed}" / "checkpoint.pkl").exists()
        assert not staging_path(out / name / f"seed{seed}").exists()
        assert not list((out / name / f"seed{seed}").glob(".*.tmp"))


def test_combined_front_is_the_nondominated_merge_of_the_seeds(first_batch):
    out, summary = first_batch["out"], first_batch["summary"]
    for name, keys, signs in [
        ("alpha", ["volume_m3", "gci"], np.array([-1.0, -1.0])),
        ("beta", ["band2_volume_m3", "fci"], np.array([-1.0, 1.0])),
    ]:
        combined = pd.read_csv(out / name / "combined_pareto.csv")
        seeds = pd.concat(
            [pd.read_csv(out / name / f"seed{s}" / "pareto.csv").assign(seed=s) for s in SEEDS[name]],
            ignore_index=True,
        )
        F_all = seeds[keys].to_numpy() * signs
        F = combined[keys].to_numpy() * signs
        # brute force: exactly the seeds' points that no seed point dominates, each objective vector once
        dominated = [np.any(np.all(F_all <= f, axis=1) & np.any(F_all < f, axis=1)) for f in F_all]
        expected = {tuple(f) for f, d in zip(F_all, dominated, strict=True) if not d}
        assert {tuple(f) for f in F} == expected and len(F) == len(expected)
        assert list(combined.columns[:1]) == ["seed"] and "rank" not in combined.columns
        for _, row in combined.iterrows():  # every row is a row of its own seed's front
            mine = seeds[seeds["seed"] == row["seed"]]
            assert np.any(np.all(np.isclose(mine[keys].to_numpy(), row[keys].to_numpy(dtype=float)), axis=1))
        info = summary["combined"][name]
        assert info["seeds"] == SEEDS[name] and info["pareto_size"] == len(combined)
        seed_hv = [t["hypervolume"] for t in summary["tasks"] if t["config"] == name]
        assert info["hypervolume"] >= max(seed_hv) - 1e-12
        png = (out / name / "hypervolume_by_seed.png").read_bytes()
        assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 5000


def test_rerun_skips_finished_tasks(first_batch):
    out = first_batch["out"]
    before = {p: (p.stat().st_mtime_ns, p.read_bytes()) for p in out.glob("*/seed*/*") if p.is_file()}
    r = CliRunner().invoke(app, first_batch["args"])
    assert r.exit_code == 1, r.output  # the failing tasks fail again
    tasks = _tasks(json.loads((out / "batch.json").read_text()))
    for key in [("alpha", 3), ("alpha", 4), ("beta", 11), ("beta", 12)]:
        assert tasks[key]["status"] == "skipped", tasks[key]
    for key, t in _tasks(first_batch["summary"]).items():
        if t["status"] == "finished":
            assert tasks[key]["hypervolume"] == t["hypervolume"]
    assert [tasks[("nobounds", s)]["status"] for s in (3, 4)] == ["failed", "failed"]
    after = {p: (p.stat().st_mtime_ns, p.read_bytes()) for p in out.glob("*/seed*/*") if p.is_file()}
    assert after == before  # skipped tasks leave their directories untouched
    assert " skipped " in r.output


def test_embedded_local_cluster(tmp_path):
    """Without --scheduler the batch starts (and stops) its own LocalCluster."""
    cfg = config_from_dict({**copy.deepcopy(SMALL), "name": "solo", "algorithm": {"pop_size": 8, "n_gen": 2}})
    lines = []
    summary = run_batch([("solo.yaml", cfg)], tmp_path, seeds=2, echo=lines.append)
    assert summary.scheduler == "local" and summary.n_failed == 0
    assert [(t.status, t.seed) for t in summary.tasks] == [("finished", 1), ("finished", 2)]
    # one progress line per task as it completes: [done/total], in completion order
    assert [ln[:6] for ln in lines] == ["[1/2] ", "[2/2] "]
    assert sorted(ln[6:] for ln in lines) == [
        f"solo seed {t.seed}: finished (HV {t.hypervolume:.6g}, {t.wall_seconds:.1f} s)" for t in summary.tasks
    ]
    assert json.loads((tmp_path / "batch.json").read_text())["n_finished"] == 2
    # the workers got NUMBA_NUM_THREADS so that workers x Numba threads <= cores (the manifest records it)
    _, threads = local_cluster_shape(2)
    for seed in (1, 2):
        manifest = json.loads((tmp_path / "solo" / f"seed{seed}" / "manifest.json").read_text())
        assert manifest["machine"]["numba_threads"] == threads


@pytest.mark.parametrize(
    ("tasks", "cores", "expected"),
    [(1, 2, (1, 2)), (2, 2, (2, 1)), (8, 2, (2, 1)), (3, 8, (3, 2)), (5, 16, (5, 3)), (4, 1, (1, 1))],
)
def test_local_cluster_never_oversubscribes(tasks, cores, expected):
    workers, threads = local_cluster_shape(tasks, cores)
    assert (workers, threads) == expected and workers * threads <= cores


def test_combined_front_by_hand():
    """Two seeds' fronts of (max a, min b): the merge keeps the non-dominated points once, lowest seed first."""
    s1 = pd.DataFrame({"a": [1.0, 2.0], "b": [0.5, 1.0], "rank": [0, 0]})
    s2 = pd.DataFrame({"a": [3.0, 2.0, 1.5], "b": [2.0, 1.0, 1.5], "rank": [0, 0, 0]})
    front = combined_front({2: s2, 1: s1}, ["a", "b"], np.array([-1.0, 1.0]))
    # minimisation form (-a, b): (-3, 2) s2, (-2, 1) s1 and s2 (kept once: seed 1), (-1, 0.5) s1; (-1.5, 1.5) is
    # dominated by (-2, 1)
    assert front.to_dict("list") == {"seed": [2, 1, 1], "a": [3.0, 2.0, 1.0], "b": [2.0, 1.0, 0.5]}
    assert nondominated_mask(np.array([[0.0, 1.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])).tolist() == [
        True, True, False, True,
    ]


def test_table_format():
    from scalesynth.batch import TaskRecord

    rows = [
        TaskRecord("a", "a.yaml", 1, "out/a/seed1", "finished", wall_seconds=1.5, hypervolume=2.5),
        TaskRecord("bb", "b.yaml", 2, "out/bb/seed2", "failed", error="bounds: at least one"),
    ]
    assert format_table(rows).splitlines() == [
        "config  seed  status    wall_s  hypervolume  results       error",
        "a       1     finished  1.5     2.5          out/a/seed1",
        "bb      2     failed    0.0     -            out/bb/seed2  bounds: at least one",
    ]


def test_ci_workflow_runs_a_small_batch_and_uploads_its_directory(root):
    """The example workflow installs the dask extra, runs quick.yaml x 2 seeds and uploads that batch directory."""
    wf = yaml.safe_load((root / ".github" / "workflows" / "synthesis.yml").read_text())
    steps = wf["jobs"]["batch"]["steps"]
    runs = "\n".join(s.get("run", "") for s in steps)
    assert 'pip install -e ".[dask]"' in runs
    assert "scalesynth batch configs/quick.yaml --seeds 2 --out results/ci-batch" in runs
    (upload,) = [s for s in steps if s.get("uses", "").startswith("actions/upload-artifact")]
    assert upload["with"]["path"].rstrip("/") == "results/ci-batch" and upload["if"] == "always()"
    assert (root / "configs" / "quick.yaml").is_file()


def test_unreachable_scheduler_is_a_one_line_error_exit_1(tmp_path, monkeypatch):
    from scalesynth import cluster

    monkeypatch.setattr(cluster, "CONNECT_SECONDS", 1.0)
    cfg_path = _write(tmp_path / "alpha.yaml", ALPHA)
    t0 = time.monotonic()
    r = CliRunner().invoke(app, ["batch", str(cfg_path), "--out", str(tmp_path / "out"),
                                 "--scheduler", "tcp://127.0.0.1:9"])
    assert time.monotonic() - t0 < 30  # bounded by CONNECT_SECONDS (1 s here), not dask's retries forever
    assert r.exit_code == 1, r.output
    lines = r.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: --scheduler tcp://127.0.0.1:9: cannot connect"), lines
    assert not (tmp_path / "out").exists()


def test_lost_chunks_are_resubmitted_from_the_clients_checkpoint(tmp_path, monkeypatch, sequential):
    """The client's chunk driver with real chunks run in this process and dask's failures injected: a chunk that
    dask gives up on (KilledWorker) is resubmitted with the checkpoint the client wrote, and the task ends
    byte-identical to a sequential run; a task whose chunks are always killed fails alone after MAX_RESUBMITS
    resubmissions, its checkpoint kept on the client; retries come from the scheduler's remove-worker events."""
    from distributed.scheduler import KilledWorker

    from scalesynth import batch
    from scalesynth.batch_task import run_chunk

    def inject(fn, args, key):
        data, seed, _ = args
        assert fn is run_chunk
        assert str(tmp_path) not in repr(data)  # a chunk never gets a client path: OUT stays the client's
        n_seed = sum(c[1][1] == seed for c in client.calls)
        if (seed, n_seed) == (3, 2) or seed == 4 and n_seed > 1:  # killed: the scheduler logs the lost chunk
            client.events.append((float(len(client.calls)), {"action": "remove-worker", "worker": "tcp://dead:1",
                                                             "processing-tasks": [key], "expected": False}))
            return KilledWorker(key, None, 3)
        return None

    use_inline_dask(monkeypatch)
    monkeypatch.setattr(batch, "PROGRESS_EVERY", 0.0)  # a progress line after every checkpoint
    client = InlineClient(inject=inject)
    tasks = batch.plan([("alpha.yaml", config_from_dict(copy.deepcopy(ALPHA)))], 2, tmp_path)
    lines = []
    records = batch.run_tasks(tasks, client, lines.append)
    ok, lost = records
    assert ok.status == "finished" and ok.retries == 1 and ok.lost_workers == ["tcp://dead:1"]
    for f in ("pareto.csv", "population.csv"):
        assert (tmp_path / "alpha" / "seed3" / f).read_bytes() == (sequential[("alpha", 3)] / f).read_bytes()
    # SMALL: 6 generations, a checkpoint every 2 -> chunks end at generations 2, 4, 6; the killed second chunk is
    # resubmitted with the checkpoint of generation 2 that the first chunk returned
    calls = [(args[1], args[2], key, kwargs) for _, args, key, kwargs in client.calls]
    assert all(kw["allow_other_workers"] is True and len(kw["workers"]) == 1 for *_, kw in calls)
    seed3 = [(ck, key) for s, ck, key, _ in calls if s == 3]
    assert [key.rsplit("-", 2)[1] for _, key in seed3] == ["gen0", "gen2", "gen2", "gen4"]
    assert seed3[0][0] is None and seed3[1][0] == seed3[2][0] and seed3[1][0] is not None
    import numba

    pool = int(numba.config.NUMBA_NUM_THREADS)  # outside a dask worker a chunk takes Numba's whole pool
    assert ok.chunks == 3 and ok.numba_threads == pool
    assert ok.workers == [{"address": "local", "name": "local", "nthreads": pool, "numba_threads": pool, "chunks": 3}]
    assert lost.status == "failed" and lost.retries == batch.MAX_RESUBMITS + 1
    assert lost.error.startswith("workers kept dying while running generations after 2 (dask's KilledWorker 4 times)")
    seed4 = [ck for s, ck, _, _ in calls if s == 4]
    assert (staging_path(tmp_path / "alpha" / "seed4") / "checkpoint.pkl").read_bytes() == seed4[1]
    assert not (tmp_path / "alpha" / "seed4" / "manifest.json").exists()
    assert sum("worker tcp://dead:1 lost while running generations after 2" in ln for ln in lines) == 5
    # one progress line per checkpoint (PROGRESS_EVERY 0): both first chunks run at once (two idle workers), seed 3
    # reaches 2, seed 4 reaches 2 (its later chunks are all killed), seed 3 reaches 4; 2 x 6 generations in all.
    # The other task's chunk is in flight each time.
    assert [ln for ln in lines if ln.startswith("progress: ")] == [
        "progress: 0/2 tasks ended, 1 chunks running, generations 2/12 (17 %)",
        "progress: 0/2 tasks ended, 1 chunks running, generations 4/12 (33 %)",
        "progress: 0/2 tasks ended, 1 chunks running, generations 6/12 (50 %)",
    ]


def test_without_dask_the_batch_says_how_to_install_it(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "dask.distributed", None)  # makes `import dask.distributed` fail
    cfg_path = _write(tmp_path / "alpha.yaml", ALPHA)
    r = CliRunner().invoke(app, ["batch", str(cfg_path), "--out", str(tmp_path / "out")])
    assert r.exit_code == 1
    assert r.output.strip() == "error: batch needs dask.distributed: pip install 'scalesynth[dask]'"
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    ("address", "problem"),
    [
        ("tcp://127.0.0.1:notaport", "port 'notaport' is not a number in 1..65535"),
        ("tcp://127.0.0.1:0", "port '0' is not a number in 1..65535"),
        ("tcp://127.0.0.1:70000", "port '70000' is not a number in 1..65535"),
        ("foo bar", "expected SCHEME://HOST:PORT, e.g. tcp://10.0.0.5:8786"),
        ("tcp://127.0.0.1", "expected SCHEME://HOST:PORT, e.g. tcp://10.0.0.5:8786"),
        ("tcp://:8786", "expected SCHEME://HOST:PORT, e.g. tcp://10.0.0.5:8786"),
        ("http://127.0.0.1:8786", "unknown protocol 'http' (use tcp, tls, ws, wss, ucx)"),
    ],
)
def test_a_malformed_scheduler_address_is_bad_input_exit_2(tmp_path, address, problem):
    cfg_path = _write(tmp_path / "alpha.yaml", ALPHA)
    r = CliRunner().invoke(app, ["batch", str(cfg_path), "--out", str(tmp_path / "out"), "--scheduler", address])
    assert r.exit_code == 2, r.output
    assert r.output.strip().splitlines() == [f"error: --scheduler: {address!r}: {problem}"]
    assert not (tmp_path / "out").exists()


def test_scheduler_addresses_are_normalised():
    from scalesynth.cluster import check_address

    assert check_address("127.0.0.1:8786") == "tcp://127.0.0.1:8786"
    assert check_address(" tls://node-7.cluster:08786 ") == "tls://node-7.cluster:8786"
    assert check_address("tcp://[::1]:8786") == "tcp://[::1]:8786"


@pytest.mark.parametrize(
    ("content", "problem"),
    [
        (None, "cannot read (No such file or directory)"),
        ("{not json", "not a dask scheduler file (invalid JSON)"),
        ('{"id": "Scheduler-1"}', "not a dask scheduler file (no 'address')"),
        ('{"address": "tcp://127.0.0.1:x"}', None),
    ],
)
def test_a_bad_scheduler_file_is_bad_input_exit_2(tmp_path, content, problem):
    cfg_path = _write(tmp_path / "alpha.yaml", ALPHA)
    sched = tmp_path / "scheduler.json"
    if content is not None:
        sched.write_text(content)
    r = CliRunner().invoke(app, ["batch", str(cfg_path), "--out", str(tmp_path / "out"), "--scheduler-file",
                                 str(sched)])
    assert r.exit_code == 2, r.output
    expected = (f"error: --scheduler-file {sched}: {problem}" if problem
                else "error: --scheduler: 'tcp://127.0.0.1:x': port 'x' is not a number in 1..65535")
    assert r.output.strip().splitlines() == [expected]
    r = CliRunner().invoke(app, ["batch", str(cfg_path), "--out", str(tmp_path / "out"), "--scheduler-file",
                                 str(sched), "--scheduler", "tcp://127.0.0.1:8786"])
    assert r.exit_code == 2 and r.output.strip() == "error: --scheduler, --scheduler-file: give one of them"
    assert not (tmp_path / "out").exists()


def test_a_worker_without_scalesynth_or_with_other_versions_is_named():
    """check_workers compares dask's package report of every worker with the client's: the first differing worker
    is named with what differs, on one line (a RunError: exit 1, before any task is submitted)."""
    from scalesynth.cluster import CHECKED_PACKAGES, check_workers, client_versions

    mine = client_versions()
    ok = {"packages": {"python": sys.version.split()[0] + ".final.0", **{p: mine[p] for p in CHECKED_PACKAGES}}}

    class Client:
        def __init__(self, workers):
            self.workers = workers

        def scheduler_info(self, n_workers=5):
            assert n_workers == -1  # every worker, not the first five
            return {"workers": {a: {"name": f"n{i}", "nthreads": 2} for i, a in enumerate(sorted(self.workers))}}

        def get_versions(self, packages):
            assert set(packages) == set(CHECKED_PACKAGES)
            return {"workers": self.workers}

    good = {"tcp://10.0.0.1:1": ok, "tcp://10.0.0.2:1": ok}
    assert check_workers(Client(good)) == {"tcp://10.0.0.1:1": {"name": "n0", "nthreads": 2},
                                           "tcp://10.0.0.2:1": {"name": "n1", "nthreads": 2}}
    lacking = {"packages": {**ok["packages"], "scalesynth": None}}
    older = {"packages": {**ok["packages"], "numba": "0.60.0", "pymoo": "0.6.0"}}
    with pytest.raises(RunError) as err:
        check_workers(Client({**good, "tcp://10.0.0.3:1": lacking}))
    assert str(err.value) == f"worker tcp://10.0.0.3:1 (n2): scalesynth not installed (client {mine['scalesynth']})"
    with pytest.raises(RunError) as err:
        check_workers(Client({"tcp://10.0.0.1:1": ok, "tcp://10.0.0.4:1": older, "tcp://10.0.0.5:1": lacking}))
    assert str(err.value) == (f"worker tcp://10.0.0.4:1 (n1): numba 0.60.0 (client {mine['numba']}); pymoo 0.6.0 "
                              f"(client {mine['pymoo']}) (and 1 more workers)")


def test_a_task_uses_its_workers_thread_count_capped_by_numbas_pool():
    import numba

    from scalesynth.batch_task import set_numba_threads, worker_identity

    before = numba.get_num_threads()
    try:
        assert set_numba_threads(1) == 1 == numba.get_num_threads()
        # more than the pool Numba started with (NUMBA_NUM_THREADS): the whole pool, never an error
        assert set_numba_threads(10**6) == numba.config.NUMBA_NUM_THREADS
    finally:
        numba.set_num_threads(before)
    # outside a dask worker (a direct call): Numba's pool size stands in for the worker's threads
    assert worker_identity() == {"address": "local", "name": "local", "nthreads": numba.config.NUMBA_NUM_THREADS,
                                 "local_directory": None}
