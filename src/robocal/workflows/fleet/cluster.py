"""The Dask side of ``robocal fleet``: a client on a local cluster (default) or on a user's cluster
by address, and running a list of tasks on it with progress.

dask.distributed is the ``fleet`` extra and imported only here, when a fleet command runs (never by
``robocal --help``). Tasks are plain module-level functions of small, picklable arguments (paths,
options): what travels to a worker is the task description, not the data.
"""

from __future__ import annotations
from ...errors import RobocalError

import contextlib
import os
import queue
import shutil
import tempfile
import time
import uuid

__all__ = ["LOCAL_CLUSTER_CONFIG", "FleetClusterError", "import_distributed", "fleet_client", "run_tasks", "run_pulled",
           "pull_items", "worker_threads", "default_workers", "tls_security"]

FLEET_EXTRA_HINT = "pip install 'robocal[fleet]'"


class FleetClusterError(RobocalError, RuntimeError):
    """The Dask cluster cannot be used (not installed, not reachable)."""


def import_distributed():
    """``dask.distributed``, or a clear error naming the extra."""
    try:
        import distributed
    except ImportError as exc:
        raise FleetClusterError(f"robocal fleet needs dask.distributed (the 'fleet' extra: {FLEET_EXTRA_HINT}): "
                                f"{exc}") from None
    return distributed


def default_workers() -> int:
    """Worker processes of the default local cluster: one per CPU this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return max(1, os.cpu_count() or 1)


def tls_security(*, ca_file=None, cert=None, key=None, security_file=None):
    """A ``distributed.security.Security`` for a TLS cluster (encryption required), or None when no
    option is given. ca_file, cert, key: PEM files (the cluster's CA, this client's certificate and
    its private key; the key may sit in the certificate file). security_file: a TOML file with
    ``[tls]`` ``ca_file``, ``cert``, ``key`` (paths relative to the file); options override it.
    :class:`FleetClusterError` naming a missing file."""
    import tomllib
    from pathlib import Path

    values = {}
    if security_file is not None:
        path = Path(security_file)
        try:
            data = tomllib.loads(path.read_text(encoding="utf-8-sig"))
        except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
            raise FleetClusterError(f"--security {path}: cannot read it as TOML: {exc}") from None
        tls = data.get("tls")
        if not isinstance(tls, dict) or not {"ca_file", "cert"} <= set(tls):
            raise FleetClusterError(f"--security {path}: needs a [tls] table with ca_file and cert (and key unless "
                                    "the certificate file holds it)")
        values = {k: str((path.parent / str(tls[k])).resolve()) for k in ("ca_file", "cert", "key") if k in tls}
    for k, v in (("ca_file", ca_file), ("cert", cert), ("key", key)):
        if v is not None:
            values[k] = str(v)
    if not values:
        return None
    if "ca_file" not in values or "cert" not in values:
        raise FleetClusterError("TLS needs --tls-ca-file and --tls-cert (and --tls-key unless the certificate "
                                "file holds the key), or --security FILE")
    for k, v in values.items():
        if not Path(v).is_file():
            raise FleetClusterError(f"TLS {k} file {v}: no such file")
    distributed = import_distributed()
    return distributed.security.Security(require_encryption=True, tls_ca_file=values["ca_file"],
                                         tls_client_cert=values["cert"], tls_client_key=values.get("key"))


@contextlib.contextmanager
def fleet_client(scheduler: str | None = None, workers: int | None = None, *, processes: bool = True,
                 security=None):
    """A ``distributed.Client``: on the cluster at ``scheduler`` (``tcp://host:8786``), or on a new
    local cluster of ``workers`` (default :func:`default_workers`) single-threaded worker processes
    (``processes=False``: threads in this process, for tests), closed on exit. No dashboard is
    started for a local cluster (a shared machine may have its port taken). security: a
    ``distributed.security.Security`` (:func:`tls_security`) for a scheduler at ``tls://``.

    A scheduler and its workers must be trusted: Dask runs pickled code and unpickles results
    (docs/fleet.md, "Trust boundary"). Without TLS the traffic, results included, is in clear."""
    distributed = import_distributed()
    if scheduler is not None and workers is not None:
        raise FleetClusterError("give either --scheduler (an existing cluster) or --workers (a local one), not both")
    if workers is not None and workers < 1:
        raise FleetClusterError(f"--workers must be at least 1, got {workers}")
    if security is not None and (scheduler is None or not str(scheduler).startswith("tls://")):
        raise FleetClusterError("TLS options need --scheduler tls://host:port (the cluster's TLS address)")
    if scheduler is not None:
        try:
            client = distributed.Client(scheduler, timeout="20s", **({"security": security} if security else {}))
        except (OSError, TimeoutError) as exc:
            raise FleetClusterError(f"cannot reach the Dask scheduler at {scheduler}: {exc}") from None
        with client:
            yield client
        return
    n = workers or default_workers()
    import dask

    # Dask's background work held low (LOCAL_CLUSTER_CONFIG); the nannies ship the settings to the
    # worker processes.
    with dask.config.set(LOCAL_CLUSTER_CONFIG), distributed.LocalCluster(
            n_workers=n, threads_per_worker=1, processes=processes, dashboard_address=None, silence_logs=40,
            scheduler_sync_interval=LOCAL_SCHEDULER_SYNC_S) as cluster:
        quiet_local_scheduler(cluster.scheduler)
        with distributed.Client(cluster) as client:
            yield client


#: Seconds between two heartbeats of a worker of the local cluster (Dask: 0.5 s up to 10 workers).
#: A heartbeat cost its worker ~5 ms of CPU (metrics gathered, sent, answered) and the scheduler
#: its handling: with two workers ~25 ms of CPU per second, on the cores the tasks need
#: (benchmarks/README.md). Dask itself spaces them by up to several seconds on large clusters; a
#: worker that dies is still noticed at once (its nanny and its connection), and the scheduler's
#: worker time-to-live (5 min) is far longer.
LOCAL_HEARTBEAT_S = 5.0
#: Seconds between the local cluster object's syncs of its description to the scheduler (Dask: 1 s).
LOCAL_SCHEDULER_SYNC_S = 10
#: Seconds between the local scheduler's idle and no-workers checks (Dask: 0.25 s).
LOCAL_IDLE_CHECK_S = 5.0


def quiet_local_scheduler(scheduler) -> bool:
    """Hold the background work of ``scheduler`` (a ``distributed.Scheduler`` in this process: the
    local cluster's) low: its workers send a heartbeat every :data:`LOCAL_HEARTBEAT_S` at most often
    (its answer to a heartbeat sets the worker's next interval), and its idle and no-workers checks
    (every 250 ms; no idle or no-workers timeout is set on this cluster) run every
    :data:`LOCAL_IDLE_CHECK_S`. This scheduler only; False (nothing changed) when its handler is not
    the one expected."""
    for name in ("idle-timeout", "no-workers-timeout"):
        callback = getattr(scheduler, "periodic_callbacks", {}).get(name)
        if callback is not None:
            callback.callback_time = max(callback.callback_time, 1000 * LOCAL_IDLE_CHECK_S)
    handler = getattr(scheduler, "handlers", {}).get("heartbeat_worker")
    if handler is None or getattr(handler, "_robocal_spaced", False):
        return False

    def heartbeat_worker(*args, **kwargs):
        response = handler(*args, **kwargs)
        if isinstance(response, dict) and isinstance(response.get("heartbeat-interval"), (int, float)):
            response["heartbeat-interval"] = max(response["heartbeat-interval"], LOCAL_HEARTBEAT_S)
        return response

    heartbeat_worker._robocal_spaced = True
    scheduler.handlers["heartbeat_worker"] = heartbeat_worker
    return True


#: Dask settings of the local cluster ``robocal fleet calibrate`` starts. A fleet task is a
#: calibration of ~20-40 ms, and the local cluster shares the machine's cores with its workers, so
#: Dask's background work is the fleet's cost (benchmarks/bench_fleet.py; benchmarks/README.md):
#:
#: * the worker's statistical profiler samples every task's stack every 10 ms under the GIL
#:   (~10-15 % of the fleet's throughput on calibrations of ~40 ms);
#: * every server (scheduler, nannies, workers) runs periodic callbacks on its event loop: latency
#:   ticks every 20 ms, the system monitor every 500 ms, the memory monitors every 100 ms, the
#:   active memory manager every 2 s, the client's scheduler-info refresh every 2 s: an idle local
#:   cluster of two workers took ~150 ms of CPU per second with Dask's defaults (2026-11-27, 20 s
#:   idle, all processes, psutil), ~7 % of a two-core machine; with the settings below and
#:   :func:`quiet_local_scheduler` ~40-75 ms. The event loop still warns after 3 s without a tick
#:   (``distributed.admin.tick.limit``, above the 2 s tick); a worker above its memory limit is still
#:   paused and its nanny still restarts it, within 2 s;
#: * the GIL-contention monitor (when ``gilknocker`` is installed) samples every millisecond;
#: * work stealing books every task's transitions for a rebalancing that never applies here: the
#:   fleet's tasks have no dependencies, so the scheduler queues them and hands each worker its next
#:   task as it frees (``distributed.scheduler.worker-saturation``).
LOCAL_CLUSTER_CONFIG = {
    "distributed.worker.profile.enabled": False,
    "distributed.scheduler.work-stealing": False,
    "distributed.admin.tick.interval": "2s",
    "distributed.admin.system-monitor.interval": "60s",
    "distributed.admin.system-monitor.gil.enabled": False,
    "distributed.worker.memory.monitor-interval": "2s",
    "distributed.deploy.cluster-repr-interval": "10s",
    "distributed.client.scheduler-info-interval": "10s",
    "distributed.scheduler.active-memory-manager.start": False,
}


def run_tasks(client, fn, items, *, keys=None, progress=None, on_error=None, **kwargs) -> list:
    """``[fn(item, **kwargs) for item in items]`` as one Dask task per item (``client`` None: a plain
    loop in this process), in the order of ``items``.

    progress(done, total, result): called as each task finishes (completion order). on_error(item,
    exc): the result for a task whose worker died or whose function raised (default: re-raise).
    """
    items = list(items)
    total = len(items)
    results = [None] * total
    step = progress or (lambda done, n, result: None)

    def failed(i, exc):
        if on_error is None:
            raise exc
        return on_error(items[i], exc)

    if client is None:
        for i, item in enumerate(items):
            try:
                results[i] = fn(item, **kwargs)
            except Exception as exc:  # one failing item never stops the others
                results[i] = failed(i, exc)
            step(i + 1, total, results[i])
        return results
    distributed = import_distributed()
    futures = client.map(fn, items, key=keys, pure=False, **kwargs)
    where = {f.key: i for i, f in enumerate(futures)}
    done = 0
    # with_results: the client's event loop fetches each result as it arrives, so this thread does
    # not make one blocking round trip per robot (fut.result() cost ~5 ms of latency a robot and
    # kept the client process busy on a machine whose cores the workers need)
    for fut, result in distributed.as_completed(futures, with_results=True, raise_errors=False):
        i = where[fut.key]
        if fut.status in ("error", "cancelled") or isinstance(result, BaseException):
            # an erred future gives (type, exception, traceback); a cancelled one the exception
            exc = result[1] if isinstance(result, tuple) and len(result) == 3 else result
            if not isinstance(exc, BaseException):
                exc = RuntimeError(f"task {fut.key} ended as {fut.status}")
            results[i] = failed(i, exc)  # a worker lost (KilledWorker) or a task that raised
        else:
            results[i] = result
        done += 1
        step(done, total, results[i])
    del futures
    return results


def worker_threads(client) -> int:
    """Worker threads of ``client``'s cluster (1 when the scheduler cannot say)."""
    try:
        return max(1, sum(w.get("nthreads", 1) for w in client.scheduler_info()["workers"].values()))
    except Exception:  # an unusual client: assume one slot
        return 1


#: Event topic of :func:`run_pulled`'s progress messages (one topic for every run, so that the
#: scheduler's bounded event log does not grow by a topic per run; each run's messages carry its token).
PROGRESS_TOPIC = "robocal-fleet-progress"
#: Seconds between two progress messages of one long task (:func:`pull_items`): a message per item
#: cost ~0.8 ms of the scheduler's and client's CPU, on the cores the workers use.
PROGRESS_INTERVAL_S = 0.5
#: Above this many item copies (long tasks x items) the items travel to the workers once, scattered.
_SCATTER_ABOVE = 20_000


def _claim(claims_dir: str, index: int) -> bool:
    """True when this process is the first to claim item ``index`` (a file made with O_EXCL: atomic on
    a local disk and on NFS v3 and later)."""
    try:
        os.close(os.open(os.path.join(claims_dir, str(index)), os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600))
    except FileExistsError:
        return False
    return True


class _Raised:
    """An item's exception, returned by :func:`pull_items` in place of its result."""

    def __init__(self, exc: BaseException):
        self.exc = exc


def pull_items(task: int, fn, items, claims_dir: str, token: str, kwargs: dict,
               interval_s: float = PROGRESS_INTERVAL_S) -> list:
    """Long task number ``task`` of :func:`run_pulled`: ``fn(item, **kwargs)`` for every item of ``items`` this
    task claims first in ``claims_dir``, in order; returns ``[(index, result), ...]`` (an exception
    the function raised in place of its result). Results are
    also sent as progress events (topic :data:`PROGRESS_TOPIC`, message ``[token, [[index, result],
    ...]]``), at most one every ``interval_s`` seconds and the rest at the end. A worker sends its
    messages before its task's end on one stream and the scheduler forwards them in order, so the
    client has every result when the task ends without fetching it (one round trip through the
    scheduler to the worker, ~4 ms, saved per task); the returned list is the fallback."""
    try:
        worker = import_distributed().get_worker()
    except ValueError:  # not on a worker (a direct call)
        worker = None
    done, unsent, last = [], [], time.monotonic()
    for i, item in enumerate(items):
        if not _claim(claims_dir, i):
            continue
        try:
            result = fn(item, **kwargs)
        except Exception as exc:  # one failing item never stops the others
            done.append((i, _Raised(exc)))
            continue
        done.append((i, result))
        unsent.append([i, result])
        now = time.monotonic()
        if worker is not None and now - last >= interval_s:
            _send_progress(worker, token, unsent)
            unsent, last = [], now
    if worker is not None and unsent:  # the rest: the client then need not fetch the task's result
        _send_progress(worker, token, unsent)
    return done


def _send_progress(worker, token: str, results: list) -> None:
    try:
        worker.log_event(PROGRESS_TOPIC, [token, results])
    except TypeError:  # a result msgpack cannot carry: no progress message, the task's result still returns
        pass


def run_pulled(client, fn, items, *, claims_parent, progress=None, on_error=None, key_prefix: str = "pull",
               **kwargs) -> list:
    """``[fn(item, **kwargs) for item in items]`` on ``client``'s cluster as one long task per worker
    thread, each taking the next unclaimed item until none is left (:func:`pull_items`), in the
    order of ``items``.

    A Dask task costs the scheduler and the client ~2-4 ms of CPU and the worker a round trip; for
    items of ~20-40 ms (a fleet robot) on a machine whose cores the workers use, tasks of a few items
    each left ~10 % of the machine to Dask (benchmarks/README.md). Here the workers share the items
    through claim files in a temporary folder made in ``claims_parent`` (a folder every worker sees,
    e.g. the output folder; removed at the end) and report progress in batches.

    progress(done, total, result): as results arrive (at most every :data:`PROGRESS_INTERVAL_S` per
    task, the rest when a task ends). Results travel in the progress messages (msgpack: a tuple
    arrives as a list); a task's own result is fetched only when they did not carry all.
    on_error(item, exc): the result of an item whose function raised (default: re-raise). Items a lost worker had claimed run again as one task each
    (:func:`run_tasks`); ``fn`` must tolerate that (a fleet robot already finished is skipped by its
    input hash).
    """
    items = list(items)
    total = len(items)
    results, have = [None] * total, [False] * total
    if not items:
        return results
    import_distributed()  # a clear error naming the extra
    token = uuid.uuid4().hex
    inbox = queue.Queue()
    done = 0

    def take(i, result):
        nonlocal done
        if isinstance(result, _Raised):
            if on_error is None:
                raise result.exc
            result = on_error(items[i], result.exc)
        if not have[i]:
            have[i], results[i] = True, result
            done += 1
            if progress is not None:
                progress(done, total, result)

    def on_event(event):
        msg = event[1]
        if isinstance(msg, (list, tuple)) and len(msg) == 2 and msg[0] == token:
            inbox.put(msg[1])

    n_tasks = min(total, worker_threads(client))
    claims = tempfile.mkdtemp(prefix=".robocal-claims-", dir=os.fspath(claims_parent))
    subscribed = False
    try:
        # scattered as one object (a list given to scatter would become one future per item)
        shared = client.scatter([items], broadcast=False, hash=False)[0] if n_tasks * total > _SCATTER_ABOVE else items
        # one message for all tasks, then the subscription: the client batches its messages to the
        # scheduler 10 ms apart, and a subscription sent first held the tasks back until then (the
        # first progress message comes after PROGRESS_INTERVAL_S or at a task's end; one the
        # subscription missed is made up for by the task's result)
        futures = client.map(pull_items, range(n_tasks), fn=fn, items=shared, claims_dir=claims, token=token,
                             kwargs=kwargs, key=[f"{key_prefix}-{k}-{token}" for k in range(n_tasks)], pure=False)
        client.subscribe_topic(PROGRESS_TOPIC, on_event)
        subscribed = True
        for fut in futures:
            fut.add_done_callback(lambda _f: inbox.put(None))
        ended = 0
        while ended < n_tasks:
            batch = inbox.get()
            if batch is None:
                ended += 1
                continue
            for i, result in batch:
                take(int(i), result)
        if not all(have):  # results no message carried (an item that raised, a result msgpack cannot carry)
            for fut in futures:
                if fut.status == "finished":
                    for i, result in fut.result():
                        take(i, result)
        del futures
    finally:
        if subscribed:  # Dask raises on a topic never subscribed, which would hide the error on its way
            client.unsubscribe_topic(PROGRESS_TOPIC)
        shutil.rmtree(claims, ignore_errors=True)
    missing = [i for i in range(total) if not have[i]]
    if missing:  # a long task that raised or whose worker was lost: its items again, one task each
        again = run_tasks(client, fn, [items[i] for i in missing], on_error=on_error,
                          keys=[f"{key_prefix}-again-{i}-{token}" for i in missing], **kwargs)
        for i, result in zip(missing, again):
            take(i, result)
    return results
