"""Connecting ``scalesynth batch`` to dask: scheduler address checks, an embedded LocalCluster sized to the machine,
and the check that every worker runs the client's versions of scalesynth and the packages its results depend on.

dask is an optional dependency (``pip install scalesynth[dask]``): it is imported only here and in scalesynth.batch,
lazily.
"""

from __future__ import annotations

import json
import logging
import os
import re
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from scalesynth.errors import ConfigError, RunError

CONNECT_SECONDS = 20.0  # for --scheduler: every wait to reach the scheduler and hear from it ends within this
SCHEMES = ("tcp", "tls", "ws", "wss", "ucx")
_HOST = re.compile(r"^(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_.-]+)$")
# packages whose versions must match between client and workers for byte-identical results (+ scalesynth itself)
CHECKED_PACKAGES = ("scalesynth", "numpy", "numba", "llvmlite", "pymoo", "moocore", "pandas", "pydantic", "pyyaml")


def check_address(address: str) -> str:
    """A dask scheduler address as ``scheme://host:port`` (the scheme defaults to tcp); ConfigError (exit 2)
    naming --scheduler if it is malformed."""
    text = address.strip()
    scheme, sep, rest = text.partition("://")
    if not sep:
        scheme, rest = "tcp", text
    host, colon, port = rest.rpartition(":")
    problem = None
    if scheme not in SCHEMES:
        problem = f"unknown protocol {scheme!r} (use {', '.join(SCHEMES)})"
    elif not colon or not host or not _HOST.match(host):
        problem = "expected SCHEME://HOST:PORT, e.g. tcp://10.0.0.5:8786"
    elif not port.isdigit() or not 1 <= int(port) <= 65535:
        problem = f"port {port!r} is not a number in 1..65535"
    if problem:
        raise ConfigError(f"--scheduler: {address!r}: {problem}")
    return f"{scheme}://{host}:{int(port)}"


def address_from_file(path: Path) -> str:
    """The scheduler address in a dask scheduler file (``dask scheduler --scheduler-file``, dask-mpi);
    ConfigError (exit 2) naming --scheduler-file if it cannot be read or holds no valid address."""
    try:
        info = json.loads(Path(path).read_text(encoding="utf-8"))
    except OSError as err:
        raise ConfigError(f"--scheduler-file {path}: cannot read ({err.strerror or err})") from None
    except (json.JSONDecodeError, UnicodeDecodeError):
        raise ConfigError(f"--scheduler-file {path}: not a dask scheduler file (invalid JSON)") from None
    address = info.get("address") if isinstance(info, dict) else None
    if not isinstance(address, str):
        raise ConfigError(f"--scheduler-file {path}: not a dask scheduler file (no 'address')")
    return check_address(address)


def local_cluster_shape(n_tasks: int, cores: int | None = None) -> tuple[int, int]:
    """(worker processes, threads per worker) for an embedded cluster: workers x threads <= cores. Each task's
    Numba kernels use its worker's threads."""
    cores = max(1, cores or os.cpu_count() or 1)
    workers = max(1, min(n_tasks, cores))
    return workers, max(1, cores // workers)


def _dask():
    try:
        import dask.distributed as distributed
    except ImportError:
        raise RunError("batch needs dask.distributed: pip install 'scalesynth[dask]'") from None
    return distributed


def check_protocol(address: str) -> None:
    """ConfigError (exit 2, one line) naming --scheduler when this installation cannot speak the address's protocol:
    ucx without distributed-ucxx (dask removed its own UCX support), tls and wss without TLS certificates in the
    dask configuration (``distributed.comm.tls.*``)."""
    scheme = address.partition("://")[0]
    if scheme == "ucx":
        import importlib.util

        if importlib.util.find_spec("distributed_ucxx") is None:
            raise ConfigError(f"--scheduler {address}: the ucx protocol is not available here (dask needs the "
                              "distributed-ucxx package for it); use tcp://")
    elif scheme in ("tls", "wss"):
        _dask()
        from distributed.security import Security

        if Security().get_connection_args("client").get("ssl_context") is None:
            raise ConfigError(f"--scheduler {address}: the {scheme} protocol needs TLS certificates in the dask "
                              "configuration (distributed.comm.tls.ca-file, client.cert), and none are set")


def probe_scheduler(address: str, seconds: float) -> None:
    """Connect to ``address`` and ask it for its identity, all within ``seconds``: RunError (exit 1, one line) if it
    cannot be reached or does not answer in time. dask's own Client bounds only the connection, so a port that
    accepts and never answers would make it wait for ever."""
    import asyncio
    import threading

    from distributed.comm import connect

    _refused_at_once(address, seconds)

    async def identity():
        comm = await connect(address, timeout=seconds)
        try:
            await comm.write({"op": "identity", "reply": True})
            return await comm.read()
        finally:
            comm.abort()

    outcome: dict[str, Any] = {}

    def run() -> None:  # its own thread and event loop: the caller may be inside one (a notebook)
        try:
            outcome["reply"] = asyncio.run(asyncio.wait_for(identity(), seconds))
        except BaseException as err:  # noqa: BLE001 - reported by the caller
            outcome["error"] = err

    thread = threading.Thread(target=run, name="scalesynth-scheduler-probe", daemon=True)
    thread.start()
    thread.join(seconds + 5.0)  # wait_for ends the probe at ``seconds``; the margin covers its clean-up
    err = outcome.get("error")
    if thread.is_alive() or isinstance(err, (asyncio.TimeoutError, TimeoutError)):
        raise RunError(f"--scheduler {address}: no answer within {seconds:g} s (is a dask scheduler listening "
                       "there?)")
    if err is not None:
        from scalesynth.batch_task import one_line

        raise RunError(f"--scheduler {address}: cannot connect ({one_line(err)})")
    if not isinstance(outcome.get("reply"), dict):
        raise RunError(f"--scheduler {address}: the answer is not a dask scheduler's")


def _refused_at_once(address: str, seconds: float) -> None:
    """RunError 'cannot connect' when a tcp:// address refuses the connection: dask's connect retries a refused
    port until its timeout, which would read as 'no answer'. Other outcomes are left to the identity probe."""
    import socket
    from urllib.parse import urlsplit

    parts = urlsplit(address)
    if parts.scheme != "tcp" or parts.hostname is None or parts.port is None:
        return
    try:
        socket.create_connection((parts.hostname, parts.port), timeout=seconds).close()
    except ConnectionRefusedError:
        raise RunError(f"--scheduler {address}: cannot connect (connection refused: is a dask scheduler listening "
                       "there?)") from None
    except OSError:
        return


@contextmanager
def dask_client(scheduler: str | None, n_tasks: int) -> Iterator[Any]:
    """A dask Client: on the cluster at ``scheduler`` (used as it is; one that cannot be reached, or does not answer,
    within CONNECT_SECONDS is a RunError), else on an embedded LocalCluster of worker processes with ``threads``
    threads each and NUMBA_NUM_THREADS = threads, so the machine is not oversubscribed."""
    distributed = _dask()
    if scheduler:
        address = check_address(scheduler)
        check_protocol(address)
        probe_scheduler(address, CONNECT_SECONDS)
        try:
            client = distributed.Client(address, timeout=f"{CONNECT_SECONDS}s", set_as_default=False)
        except (OSError, TimeoutError, ValueError) as err:
            from scalesynth.batch_task import one_line

            raise RunError(f"--scheduler {scheduler}: cannot connect ({one_line(err)})") from None
        with client:
            yield client
        return
    workers, threads = local_cluster_shape(n_tasks)
    cluster = distributed.LocalCluster(
        n_workers=workers,
        threads_per_worker=threads,
        processes=True,
        # the scheduler always serves HTTP (health routes): a free port, not the default 8787; no dashboard
        dashboard_address=":0",
        scheduler_kwargs={"dashboard": False},
        silence_logs=logging.ERROR,
        env={"NUMBA_NUM_THREADS": str(threads)},
    )
    with cluster, distributed.Client(cluster, set_as_default=False) as client:
        yield client


def _major_minor(python: str | None) -> str | None:
    return ".".join(python.split(".")[:2]) if python else None


def client_versions() -> dict[str, str | None]:
    """This process's versions of CHECKED_PACKAGES and Python (major.minor), as dask reports them."""
    from distributed.versions import get_package_info

    info = get_package_info(CHECKED_PACKAGES)
    return {"python": _major_minor(info.get("python")), **{p: info.get(p) for p in CHECKED_PACKAGES}}


def version_differences(mine: dict[str, str | None], theirs: dict[str, str | None]) -> list[str]:
    """'PACKAGE X (client Y)' for every package whose version differs ('not installed' where missing)."""
    out = []
    for pkg, want in mine.items():
        have = theirs.get(pkg)
        if have != want:
            out.append(f"{pkg} {have or 'not installed'} (client {want or 'not installed'})")
    return out


def check_workers(client) -> dict[str, dict[str, Any]]:
    """The connected workers as {address: {name, nthreads}}; RunError naming the first worker whose scalesynth or
    result-relevant packages differ from the client's (or that lacks scalesynth), and what differs."""
    info = client.scheduler_info(n_workers=-1)["workers"]
    versions = client.get_versions(packages=list(CHECKED_PACKAGES))["workers"]
    mine = client_versions()
    bad = []
    for address in sorted(versions):
        packages = (versions[address] or {}).get("packages", {})
        theirs = {"python": _major_minor(packages.get("python")), **{p: packages.get(p) for p in CHECKED_PACKAGES}}
        diff = version_differences(mine, theirs)
        if diff:
            bad.append((address, diff))
    if bad:
        address, diff = bad[0]
        name = info.get(address, {}).get("name", address)
        more = f" (and {len(bad) - 1} more workers)" if len(bad) > 1 else ""
        raise RunError(f"worker {address} ({name}): {'; '.join(diff)}{more}")
    return {a: {"name": str(w.get("name", a)), "nthreads": int(w.get("nthreads", 0))} for a, w in sorted(info.items())}
