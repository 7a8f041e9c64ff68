"""Evaluation of candidate designs for ``flexrv optimize`` on dask, with a resumable store.

Every candidate is one task: its nominal build and one build per tolerance draw
(:func:`flexrv.studies._modification_eval.modification_task` or an injected task of the
same signature). The record of a finished candidate is written atomically to
``<out>/evaluations/<id>.json``, ``id`` a hash of the candidate's design table, the
draws, the task and its options and the flexrv version: a killed run started again
with the same arguments re-asks the same candidates (the search is seeded) and reads
their records instead of recomputing them.
"""

from __future__ import annotations

import json
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

    start = time.perf_counter()
    try:
        record = {"status": "ok", "result": to_jsonable(resolve_task(task)(design, draws, options))}
    except Exception as exc:  # a failing candidate must not stop the search
        record = {"status": "failed", "error": f"{type(exc).__name__}: {exc}", "traceback": traceback.format_exc(8)}
    record["wall_time_s"] = time.perf_counter() - start
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
        self._client = self._cluster = None

    def _start(self):
        if self._client is not None:
            return
        from dask.distributed import Client, LocalCluster

        from flexrv.sweep import connect_scheduler

        if self.scheduler:
            self._client = connect_scheduler(self.scheduler)
        else:
            n = self.workers or min(2, os.cpu_count() or 1)
            self._cluster = LocalCluster(
                n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None, silence_logs=40
            )
            self._client = Client(self._cluster)

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
        self._client = self._cluster = None


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

    def key(self, design: dict, options: dict) -> str:
        from flexrv.cache import content_hash, flexrv_version

        return content_hash(design, self.draws_hash, self.task, options, flexrv_version(), length=16)

    def evaluate(self, designs: list[dict], options: dict, labels: list[dict] | None = None) -> list[dict]:
        """Records of ``designs`` (stored ones read, the others computed and stored)."""
        from flexrv.cache import atomic_write_text

        keys = [self.key(d, options) for d in designs]
        out: list[dict | None] = [None] * len(designs)
        jobs, where = [], []
        for i, k in enumerate(keys):
            path = self.dir / f"{k}.json"
            if path.exists():
                out[i] = json.loads(path.read_text())
                self.reused += 1
            elif k in where:  # the same design twice in one batch
                continue
            else:
                jobs.append((self.task, designs[i], self.draws, options))
                where.append(k)

        def done(j: int, record: dict) -> None:
            k = where[j]
            i = keys.index(k)
            record = {"id": k, "x": (labels or [{}] * len(designs))[i], **record}
            atomic_write_text(self.dir / f"{k}.json", json.dumps(record, indent=1))
            self.computed += 1

        self.runner.run(jobs, done)
        for i, k in enumerate(keys):
            if out[i] is None:
                out[i] = json.loads((self.dir / f"{k}.json").read_text())
        return out
