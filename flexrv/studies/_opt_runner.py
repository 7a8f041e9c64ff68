"""Evaluation of candidate designs for ``flexrv optimize`` on dask, with a resumable store.

Every candidate is one task: its nominal build and one build per tolerance draw
(:func:`flexrv.studies._modification_eval.modification_task` or an injected task of the
same signature). When a batch has fewer candidates than
:data:`flexrv.sweep.BATCHES_PER_WORKER` tasks per worker (the design itself at the
start, the re-evaluation of the recommended designs at the end), each candidate's draws
are split into consecutive chunks, one task each, so that every worker has work; the
first chunk builds the nominal design, the others are called with
``options["nominal"] = False`` (:func:`chunk_draws`), and the candidate's record joins
the chunks' results in draw order. The record of a finished candidate is written
atomically to ``<out>/evaluations/<id>.json``, ``id`` a hash of the candidate's design
table, the draws, the task and its options and the flexrv version: a killed run started
again with the same arguments re-asks the same candidates (the search is seeded) and
reads their records instead of recomputing them.
"""

from __future__ import annotations

import json
import math
import os
import time
import traceback
from pathlib import Path
from typing import Any, Callable

from flexrv.errors import InputError


def run_candidate(task: str, design: dict, draws: list, options: dict) -> dict[str, Any]:
    """One candidate on a worker: never raises; ``status`` ok/failed, ``result`` or ``error``."""
    from flexrv.cache import to_jsonable
    from flexrv.sweep import resolve_task

    start, cpu = time.perf_counter(), time.process_time()
    try:
        record = {"status": "ok", "result": to_jsonable(resolve_task(task)(design, draws, options))}
    except Exception as exc:  # a failing candidate must not stop the search
        record = {"status": "failed", "error": f"{type(exc).__name__}: {exc}", "traceback": traceback.format_exc(8)}
    record["wall_time_s"] = time.perf_counter() - start
    record["cpu_time_s"] = time.process_time() - cpu
    return record


class Runner:
    """Runs tasks inline (``mode="inline"``: in this process, for tests and tiny problems)
    or on dask.distributed (a LocalCluster of single-threaded worker processes, or the
    scheduler at ``scheduler``). Started lazily: a run whose candidates are all stored
    starts no cluster."""

    def __init__(self, scheduler: str | None = None, workers: int | None = None, mode: str = "dask"):
        if mode not in ("dask", "inline"):
            raise InputError(f"runner mode {mode!r}: allowed dask, inline")
        if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
            raise InputError(f"--workers {workers!r}: must be an integer >= 1")
        self.scheduler, self.workers, self.mode = scheduler, workers, mode
        self._client = self._cluster = self._config = None

    def _start(self):
        if self._client is not None:
            return
        import dask
        from dask.distributed import Client, LocalCluster

        from flexrv.sweep import DASK_CONFIG, connect_scheduler

        self._config = dask.config.set(DASK_CONFIG)  # until close()
        if self.scheduler:
            self._client = connect_scheduler(self.scheduler)
        else:
            n = self.workers or min(2, os.cpu_count() or 1)
            self._cluster = LocalCluster(
                n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None, silence_logs=40
            )
            self._client = Client(self._cluster)

    def slots(self) -> int:
        """Tasks that can run at once (0 inline: no point in splitting a candidate)."""
        if self.mode == "inline":
            return 0
        self._start()
        if self._cluster is not None:
            return len(self._cluster.workers)
        return max(1, len(self._client.scheduler_info().get("workers", {})))

    def run(self, jobs: list[tuple], on_done: Callable[[int, dict], None]) -> None:
        """Run ``run_candidate(*job)`` for every job; ``on_done(index, record)`` as each finishes."""
        if not jobs:
            return
        if self.mode == "inline":
            for i, job in enumerate(jobs):
                on_done(i, run_candidate(*job))
            return
        from dask.distributed import as_completed

        self._start()
        futures = {self._client.submit(run_candidate, *job, pure=False): i for i, job in enumerate(jobs)}
        for fut in as_completed(futures):
            try:
                record = fut.result()
            except Exception as exc:  # a worker died
                record = {"status": "failed", "error": f"worker error: {type(exc).__name__}: {exc}"}
            on_done(futures[fut], record)

    def close(self) -> None:
        if self._client is not None:
            self._client.close()
        if self._cluster is not None:
            self._cluster.close()
        if self._config is not None:
            self._config.__exit__(None, None, None)
        self._client = self._cluster = self._config = None


class Store:
    """The records of evaluated candidates under ``<out>/evaluations`` (see module docstring)."""

    def __init__(self, out: Path, task: str, draws: list, runner: Runner):
        from flexrv.cache import content_hash

        self.dir = Path(out) / "evaluations"
        self.dir.mkdir(parents=True, exist_ok=True)
        self.task, self.draws, self.runner = task, draws, runner
        self.draws_hash = content_hash(draws, length=16)
        self.computed = 0
        self.reused = 0
        self.workers_cpu_s = 0.0  #: the computed tasks' CPU time on their workers

    def key(self, design: dict, options: dict) -> str:
        from flexrv.cache import content_hash, flexrv_version

        return content_hash(design, self.draws_hash, self.task, options, flexrv_version(), length=16)

    def evaluate(self, designs: list[dict], options: dict, labels: list[dict] | None = None) -> list[dict]:
        """Records of ``designs`` (stored ones read, the others computed and stored)."""
        keys = [self.key(d, options) for d in designs]
        out: list[dict | None] = [None] * len(designs)
        todo: list[int] = []
        asked: set[str] = set()
        for i, k in enumerate(keys):
            path = self.dir / f"{k}.json"
            if path.exists():
                out[i] = json.loads(path.read_text())
                self.reused += 1
            elif k not in asked:  # the same design twice in one batch: computed once
                todo.append(i)
                asked.add(k)
        if todo:
            self._compute(todo, keys, designs, options, labels or [{}] * len(designs))
        for i, k in enumerate(keys):
            if out[i] is None:
                out[i] = json.loads((self.dir / f"{k}.json").read_text())
        return out

    def _compute(self, todo: list[int], keys: list[str], designs, options: dict, labels) -> None:
        """Run the candidates ``todo`` (chunked, :func:`chunk_draws`) and store each record
        when its last chunk is done."""
        from flexrv.cache import atomic_write_text

        chunks = chunk_draws(len(self.draws), len(todo), self.runner.slots())
        jobs, owner = [], []
        for i in todo:
            for c, (a, b) in enumerate(chunks):
                opts = options if c == 0 else {**options, "nominal": False}
                jobs.append((self.task, designs[i], self.draws[a:b], opts))
                owner.append((i, c))
        parts: dict[int, dict[int, dict]] = {i: {} for i in todo}

        def done(j: int, record: dict) -> None:
            i, c = owner[j]
            parts[i][c] = record
            self.workers_cpu_s += record.get("cpu_time_s", 0.0)
            if len(parts[i]) < len(chunks):
                return
            record = join_chunks([parts[i][c] for c in range(len(chunks))])
            k = keys[i]
            atomic_write_text(self.dir / f"{k}.json", json.dumps({"id": k, "x": labels[i], **record}, indent=1))
            self.computed += 1

        self.runner.run(jobs, done)


def chunk_draws(n_draws: int, n_candidates: int, slots: int) -> list[tuple[int, int]]:
    """Consecutive draw ranges [a, b) of one candidate's tasks: one range unless the
    candidates are fewer than :data:`flexrv.sweep.BATCHES_PER_WORKER` tasks per slot, then
    enough ranges (at most one per draw) to give every slot that many tasks."""
    from flexrv.sweep import BATCHES_PER_WORKER

    want = BATCHES_PER_WORKER * slots
    n = 1 if n_candidates >= want or n_candidates == 0 else math.ceil(want / n_candidates)
    n = max(1, min(n, n_draws))
    edges = [round(k * n_draws / n) for k in range(n + 1)]
    return [(edges[k], edges[k + 1]) for k in range(n)]


def join_chunks(records: list[dict]) -> dict[str, Any]:
    """One candidate's record from its chunks' records (in draw order): the nominal of the
    first, the draws concatenated; failed if any chunk failed (its error); wall and CPU
    times summed."""
    wall = sum(r.get("wall_time_s", 0.0) for r in records)
    cpu = sum(r.get("cpu_time_s", 0.0) for r in records)
    bad = next((r for r in records if r.get("status") != "ok"), None)
    if bad is not None:
        return {**bad, "wall_time_s": wall, "cpu_time_s": cpu}
    if len(records) == 1:
        return records[0]
    first = records[0]["result"]
    draws = {q: [v for r in records for v in r["result"]["draws"][q]] for q in first["draws"]}
    return {
        "status": "ok",
        "result": {"nominal": first["nominal"], "draws": draws},
        "wall_time_s": wall,
        "cpu_time_s": cpu,
    }
