"""Parameter sweeps on dask.distributed, resumable.

A sweep is described by a TOML spec::

    name = "modification"                 # results/<name>/ (or --out)
    preset = "rv40e"                      # preset name or design TOML path
    task = "design"                       # a registered task or "package.module:function"
    outputs = ["pin_load_rated.max_force_N", "torsional.C_W_Nm_per_arcmin"]

    [options]                             # keyword arguments of the task (optional)

    [grid]                                # cartesian product over design fields (dotted paths)
    "second_stage.modification_equidistant_mm" = [0.0, 0.005, 0.01]
    "operating.load_torque_Nm" = [100.0, 412.0]

    [[cases]]                             # and/or an explicit list of variations
    "second_stage.eccentricity_mm" = 1.0

Each case is the base design with its overrides applied. Before any case runs (and
before a cluster starts) every case's design is validated and the task's options are
checked (types, finite numbers, and the task's own ``check``, e.g. the step count of
``simulate``): a bad case refuses the sweep with a ConfigError naming the case, its
overrides and the field. At most :data:`MAX_CASES` cases. Cases are
identified by a hash of (design, task, options), so re-running the same spec skips
every case whose result file exists: kill the sweep at any point and run the same
command again to finish only the missing cases. Failed cases are recorded with their
error and do not stop the others (``retry_failed=True`` recomputes them).

Cases run in batches: one dask task evaluates several cases one after the other
(:func:`run_batch`; the base design travels once per batch with each case's
overrides, :func:`batch_size` chooses how many), and the client stores the records of
a batch as it arrives. A killed sweep loses at most its unfinished batches. The
client's CPU time (``getrusage`` of its process, every thread) and the workers' CPU
time (each batch's ``time.process_time`` on its worker) are recorded in the summary
(:class:`CpuAccount`).

A task is a function ``task(reducer, **options) -> dict`` returning a nested dict
of JSON-serialisable numbers; the spec's ``outputs`` pick dotted keys from it into
the sweep table (NetCDF + CSV) and plots.
"""

from __future__ import annotations

import importlib
import itertools
import json
import math
import os
import re
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

from flexrv.cache import atomic_write_text, content_hash
from flexrv.design import apply_overrides
from flexrv.errors import ConfigError, FlexrvError

#: Built-in tasks: name -> "module:function" (imported lazily on the worker).
TASKS: dict[str, str] = {
    "design": "flexrv.analysis.report:design_report",
    "simulate": "flexrv.sweep:simulate_task",
}


def simulate_task(reducer, model: str = "rigid", t_end: float = 0.5, dt: float | None = None) -> dict:
    """Sweep task: run a dynamic simulation and return its summary numbers."""
    from flexrv.simulation import Simulation

    options = {} if dt is None else {"dt": dt}
    results = Simulation(reducer, model=model).run(t_end=t_end, progress=False, **options)
    return results.summary()


def _check_simulate(reducer, model: str = "rigid", t_end: float = 0.5, dt: float | None = None) -> None:
    """The checks of :func:`simulate_task`'s options that need no model: the model name
    and the number of time steps (:func:`flexrv.simulation.check_step_count`)."""
    from flexrv.model.factory import MODELS
    from flexrv.simulation import DEFAULT_DT, check_step_count, check_time_options

    if model not in MODELS:
        raise ConfigError(f"options.model = {model!r}: allowed {sorted(MODELS)}")
    step = DEFAULT_DT if dt is None else dt
    check_step_count(check_time_options(reducer, t_end, step), step)


#: a task function may carry ``check(reducer, **options)``: the checks of its options that
#: need no work (run for the base design before any cluster starts)
simulate_task.check = _check_simulate

#: most cases one sweep may run (grid product plus [[cases]]); each case is validated
#: before any cluster starts, and a larger study is split into several sweeps
MAX_CASES = 20_000


_SPEC_KEYS = {"name", "preset", "task", "outputs", "options", "grid", "cases", "description"}


@dataclass
class SweepSpec:
    """A validated sweep specification (see module docstring)."""

    name: str
    preset: str
    task: str
    outputs: list[str]
    options: dict[str, Any] = field(default_factory=dict)
    grid: dict[str, list[Any]] = field(default_factory=dict)
    cases: list[dict[str, Any]] = field(default_factory=list)
    description: str = ""

    def variations(self) -> list[dict[str, Any]]:
        """All case overrides: the grid's cartesian product, then the explicit list."""
        out: list[dict[str, Any]] = []
        if self.grid:
            keys = list(self.grid)
            for values in itertools.product(*(self.grid[k] for k in keys)):
                out.append(dict(zip(keys, values)))
        out.extend(dict(c) for c in self.cases)
        return out


#: a sweep name: one path component of letters, digits, ``._-`` (results/<name>/)
_NAME_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,99}$")


def _require(cond: bool, path, key: str, message: str) -> None:
    if not cond:
        raise ConfigError(f"{path}: {key}: {message}")


def load_spec(path: str | os.PathLike) -> SweepSpec:
    """Read and validate a sweep spec TOML completely (before any case runs);
    :class:`ConfigError` names the key, the value and what is allowed."""
    from flexrv.design import parse_toml, read_text_file

    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"sweep spec {str(path)!r} does not exist")
    data = parse_toml(read_text_file(path, "sweep spec"), str(path))
    unknown = set(data) - _SPEC_KEYS
    if unknown:
        raise ConfigError(f"{path}: unknown sweep field(s) {sorted(unknown)}; allowed: {sorted(_SPEC_KEYS)}")
    for key in ("name", "preset", "task", "outputs"):
        if key not in data:
            raise ConfigError(f"{path}: missing required sweep field {key!r}")
    for key in ("name", "preset", "task", "description"):
        if key in data:
            _require(isinstance(data[key], str), path, key, f"must be a string, got {data[key]!r}")
    name = data["name"]
    _require(
        bool(_NAME_RE.match(name)) and ".." not in name,
        path,
        "name",
        f"{name!r} is not allowed: one folder name of letters, digits and ._- (no path separators, no '..'), "
        "the sweep writes to results/<name>/",
    )
    if not isinstance(data["outputs"], list) or not all(isinstance(o, str) and o for o in data["outputs"]):
        raise ConfigError(f"{path}: outputs: must be a list of dotted result keys (strings), got {data['outputs']!r}")
    _require(len(set(data["outputs"])) == len(data["outputs"]), path, "outputs", "duplicate keys")
    options = data.get("options", {})
    _require(
        isinstance(options, dict),
        path,
        "options",
        f"must be a table of keyword arguments of the task ([options]), got {options!r}",
    )
    grid = data.get("grid", {})
    _require(
        isinstance(grid, dict),
        path,
        "grid",
        f"must be a table of dotted design fields -> lists of values ([grid]), got {grid!r}",
    )
    for key, values in grid.items():
        if not isinstance(values, list) or not values:
            raise ConfigError(f"{path}: grid.{key} must be a non-empty list of values, got {values!r}")
        for v in values:
            _require(not isinstance(v, (dict, list)), path, f"grid.{key}", f"values must be scalars, got {v!r}")
    cases = data.get("cases", [])
    _require(
        isinstance(cases, list) and all(isinstance(c, dict) for c in cases),
        path,
        "cases",
        f"must be an array of tables ([[cases]]) of dotted design fields -> values, got {cases!r}",
    )
    for i, case in enumerate(cases):
        _require(bool(case), path, f"cases[{i}]", "is empty")
    if not grid and not cases:
        raise ConfigError(f"{path}: a sweep needs a [grid] or [[cases]]")
    spec = SweepSpec(
        name=name,
        preset=data["preset"],
        task=data["task"],
        outputs=list(data["outputs"]),
        options=dict(options),
        grid=dict(grid),
        cases=list(cases),
        description=str(data.get("description", "")),
    )
    if spec.task not in TASKS and ":" not in spec.task:
        raise ConfigError(
            f"{path}: task {spec.task!r} is neither a built-in task {sorted(TASKS)} nor 'module:function'"
        )
    return spec


def check_task(spec: SweepSpec) -> Callable[..., dict]:
    """Import the spec's task and check its options against its signature (before
    any case runs); ConfigError naming the task or option otherwise."""
    import inspect

    try:
        func = resolve_task(spec.task)
    except (ImportError, AttributeError, ValueError) as exc:
        raise ConfigError(f"task {spec.task!r} cannot be imported: {type(exc).__name__}: {exc}") from None
    if not callable(func):
        raise ConfigError(f"task {spec.task!r} is not a function")
    try:
        sig = inspect.signature(func)
    except (TypeError, ValueError):
        return func
    all_params = list(sig.parameters.values())
    if not all_params or all_params[0].kind not in (all_params[0].POSITIONAL_ONLY, all_params[0].POSITIONAL_OR_KEYWORD):
        raise ConfigError(f"task {spec.task!r} takes no design: a task is a function task(reducer, **options) -> dict")
    params = all_params[1:]
    if not any(p.kind is p.VAR_KEYWORD for p in params):
        allowed = [p.name for p in params if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)]
        bad = sorted(set(spec.options) - set(allowed))
        if bad:
            raise ConfigError(f"options.{bad[0]}: not an option of task {spec.task!r}; allowed: {allowed}")
        from flexrv.errors import InputError, check_options, signature_options

        try:
            check_options("options", spec.options, signature_options(func, skip=1))
        except InputError as exc:
            raise ConfigError(str(exc)) from None
    for key, value in spec.options.items():
        if isinstance(value, float) and not math.isfinite(value):
            raise ConfigError(f"options.{key} = {value!r}: must be a finite number")
    return func


def known_outputs(spec: SweepSpec, base) -> set[str] | None:
    """Dotted output keys the task produces, if knowable before running: a task
    function's ``outputs`` attribute, or (built-in ``design``) the keys of the
    design report of the base design. None if unknown (checked after the run)."""
    func = check_task(spec)
    declared = getattr(func, "outputs", None)
    if declared is not None:
        return set(declared)
    if spec.task == "design":
        from flexrv.cache import to_jsonable

        return set(_dotted_keys(to_jsonable(func(base, **spec.options))))
    return None


def _dotted_keys(node: Any, prefix: str = "") -> list[str]:
    out = []
    if isinstance(node, dict):
        for k, v in node.items():
            out += _dotted_keys(v, f"{prefix}{k}.")
    else:
        out.append(prefix[:-1])
    return out


def check_outputs(spec: SweepSpec, keys: set[str] | None) -> None:
    """ConfigError for an output key the task does not produce."""
    if keys is None:
        return
    for o in spec.outputs:
        if o not in keys:
            import difflib

            close = difflib.get_close_matches(o, sorted(keys), n=3)
            hint = f"; did you mean {', '.join(close)}?" if close else ""
            raise ConfigError(f"outputs: {o!r} is not an output of task {spec.task!r}{hint}")


# ------------------------------------------------------------------ case logic
def resolve_task(name: str) -> Callable[..., dict]:
    """Import a task function from its registered name or 'module:function'."""
    target = TASKS.get(name, name)
    module_name, _, func_name = target.partition(":")
    module = importlib.import_module(module_name)
    return getattr(module, func_name)


def pick(result: dict[str, Any], dotted: str) -> Any:
    """Value at a dotted key of a nested result dict (None if absent)."""
    node: Any = result
    for key in dotted.split("."):
        if isinstance(node, dict) and key in node:
            node = node[key]
        else:
            return None
    return node


def run_case(design: dict[str, Any], task: str, options: dict[str, Any]) -> dict[str, Any]:
    """Run one case (on a worker): validate the design, call the task, never raise.

    Returns a record with ``status`` ("ok" or "failed"), ``result`` or ``error``,
    and the wall time.
    """
    from flexrv.cache import to_jsonable
    from flexrv.design import from_dict

    start, cpu = time.perf_counter(), time.process_time()
    try:
        reducer = from_dict(design, source="sweep case")
        result = resolve_task(task)(reducer, **options)
        record = {"status": "ok", "result": to_jsonable(result)}
    except FlexrvError as exc:
        record = {"status": "failed", "error": f"{type(exc).__name__}: {exc}"}
    except Exception as exc:  # a failing case must not stop the sweep
        record = {
            "status": "failed",
            "error": f"{type(exc).__name__}: {exc}",
            "traceback": traceback.format_exc(limit=8),
        }
    record["wall_time_s"] = time.perf_counter() - start
    record["cpu_time_s"] = time.process_time() - cpu
    return record


def run_batch(
    base: dict[str, Any], overrides: list[dict[str, Any]], task: str, options: dict[str, Any]
) -> tuple[list[dict[str, Any]], float]:
    """Run a batch of cases one after the other on a worker: each case's design is
    ``base`` with its overrides (:func:`flexrv.design.apply_overrides`, the design
    :func:`build_cases` validated). Cases of one design that differ by their
    ``[errors]`` only (tolerance draws) share the model constants of the design without
    errors, computed once (:func:`flexrv.design.manufacturing.shared_nominal_constants`: the
    same numbers). Returns the records of :func:`run_case` in order and the batch's CPU
    time on the worker [s]."""
    from flexrv.design.manufacturing import shared_nominal_constants

    cpu = time.process_time()
    with shared_nominal_constants():
        records = [run_case(apply_overrides(base, o), task, options) for o in overrides]
    return records, time.process_time() - cpu


#: batches per worker of a sweep (load balance at the end of a run and granularity of
#: its checkpoints against the per-task overhead of dask)
BATCHES_PER_WORKER = 4
#: most cases in one batch (a killed sweep loses at most this many cases per worker)
MAX_BATCH = 32


#: dask settings while flexrv runs a cluster: the event loops' blocked-loop check
#: (``admin.tick``) once a second instead of every 20 ms, no statistical profiler on the
#: workers (both diagnostics for dask's dashboard, which flexrv does not start), and the
#: workers' memory polled once a second instead of ten times (a LocalCluster's nannies
#: poll from the client's process). Measured: an idle LocalCluster of 2 workers costs
#: its client process 0.73 CPU s per 20 s with dask's defaults, 0.22 with the first two,
#: 0.18 with all three.
DASK_CONFIG = {
    "distributed.admin.tick.interval": "1s",
    "distributed.worker.profile.enabled": False,
    "distributed.worker.memory.monitor-interval": "1s",
}


def batch_size(n_cases: int, n_workers: int) -> int:
    """Cases per batch: ``n_cases`` spread over :data:`BATCHES_PER_WORKER` batches per
    worker, at least 1 and at most :data:`MAX_BATCH`."""
    per = math.ceil(n_cases / (BATCHES_PER_WORKER * max(1, n_workers)))
    return max(1, min(MAX_BATCH, per))


def process_cpu_s() -> float:
    """CPU time [s] of this process so far, every thread (user + system)."""
    import resource

    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


@dataclass
class CpuAccount:
    """The CPU time of a sweep's execution: ``client_s`` of the process that submits the
    batches and stores their records (from the first submission to the last record
    stored, every thread of the process: dask's communication thread included), and
    ``workers_s``, the sum of the batches' CPU times measured on their workers."""

    client_s: float = 0.0
    workers_s: float = 0.0
    batches: int = 0
    cases: int = 0
    _start: float | None = field(default=None, repr=False)

    def start(self) -> None:
        self._start = process_cpu_s()

    def add_batch(self, worker_cpu_s: float, cases: int) -> None:
        self.workers_s += float(worker_cpu_s)
        self.batches += 1
        self.cases += int(cases)

    def stop(self) -> None:
        if self._start is not None:
            self.client_s += process_cpu_s() - self._start
            self._start = None

    @property
    def client_over_workers(self) -> float:
        """client_s / workers_s (NaN if no worker time was recorded)."""
        return self.client_s / self.workers_s if self.workers_s > 0 else math.nan

    def as_dict(self) -> dict[str, float]:
        return {
            "client_cpu_s": self.client_s,
            "workers_cpu_s": self.workers_s,
            "client_over_workers": self.client_over_workers,
            "batches": self.batches,
            "cases": self.cases,
        }


@dataclass
class Case:
    """One sweep case: its id, overrides and full design dict."""

    case_id: str
    overrides: dict[str, Any]
    design: dict[str, Any]


def case_count(spec: SweepSpec) -> int:
    """Number of cases of a spec (grid product plus [[cases]]), without expanding it."""
    return (math.prod(len(v) for v in spec.grid.values()) if spec.grid else 0) + len(spec.cases)


def build_cases(spec: SweepSpec, validate: bool = False) -> list[Case]:
    """Expand the spec into cases with stable ids (hash of design, task, options).

    With ``validate`` every case's design is validated and the task's option checks
    (a ``check`` attribute of the task function) run for it: ConfigError naming the
    case, its overrides and the field, before any case runs. More than
    :data:`MAX_CASES` cases are refused."""
    from flexrv.cache import flexrv_version

    n = case_count(spec)
    if n > MAX_CASES:
        raise ConfigError(
            f"the sweep has {n} cases (grid product {case_count(SweepSpec(**{**spec.__dict__, 'cases': []}))} "
            f"+ {len(spec.cases)} [[cases]]); at most {MAX_CASES} are allowed: split it into several sweeps"
        )
    base = base_design(spec)
    check = getattr(check_task(spec), "check", None) if validate else None
    cases = []
    for i, overrides in enumerate(spec.variations()):
        design = apply_overrides(base, overrides)
        if validate:
            _validate_case(i, overrides, design, spec, check)
        cid = content_hash(design, spec.task, spec.options, flexrv_version(), length=12)
        cases.append(Case(case_id=cid, overrides=overrides, design=design))
    return cases


def base_design(spec: SweepSpec) -> dict[str, Any]:
    """The spec's base design as a plain dict (the design every case overrides)."""
    from flexrv.design import load

    return load(spec.preset).model_dump(mode="python")


def _validate_case(i: int, overrides: dict, design: dict, spec: SweepSpec, check) -> None:
    from flexrv.design import from_dict

    shown = ", ".join(f"{k} = {v!r}" for k, v in overrides.items())
    if len(shown) > 200:
        shown = shown[:200] + " ..."
    try:
        reducer = from_dict(design, source=f"case {i} ({shown})")
        if check is not None:
            check(reducer, **spec.options)
    except FlexrvError as exc:
        text = str(exc)
        if not text.startswith("case "):
            text = f"case {i} ({shown}): {text}"
        raise ConfigError(text) from None


def case_file(out_dir: Path, case: Case) -> Path:
    return out_dir / "cases" / f"{case.case_id}.json"


def _write_case(out_dir: Path, case: Case, record: dict[str, Any]) -> None:
    payload = {"case_id": case.case_id, "overrides": case.overrides, **record}
    atomic_write_text(case_file(out_dir, case), json.dumps(payload, indent=1))


def pending_cases(out_dir: Path, cases: list[Case], retry_failed: bool = False) -> list[Case]:
    """Cases without a stored result (or failed ones with ``retry_failed``)."""
    todo = []
    for case in cases:
        path = case_file(out_dir, case)
        if not path.exists():
            todo.append(case)
            continue
        if retry_failed:
            status = json.loads(path.read_text()).get("status")
            if status != "ok":
                todo.append(case)
    return todo


# ------------------------------------------------------------------ execution
@dataclass
class SweepSummary:
    """What a sweep run did."""

    out_dir: Path
    total: int
    computed: int
    skipped: int
    failed: int
    table_csv: Path | None
    table_nc: Path | None
    plots: list[Path]
    cpu: CpuAccount = field(default_factory=CpuAccount)
    case_ids: list[str] = field(default_factory=list)  #: every case's id, in the spec's order


def run_sweep(
    spec: SweepSpec,
    out_dir: str | os.PathLike | None = None,
    scheduler: str | None = None,
    n_workers: int | None = None,
    retry_failed: bool = False,
    progress: bool = True,
    plots: bool = True,
    force: bool = False,
    batch: int | None = None,
) -> SweepSummary:
    """Run the missing cases of a sweep on dask.distributed and write the table.

    Parameters
    ----------
    spec : the sweep specification.
    out_dir : results directory (default ``results/<spec.name>``).
    scheduler : address of an existing dask scheduler; a LocalCluster with
        ``n_workers`` (default: CPU count) single-threaded worker processes otherwise.
    retry_failed : recompute cases recorded as failed.
    plots : draw one PNG per output against the first varied parameter (studies whose
        cases are random draws, e.g. the tolerance study, draw their own figures).
    force : allow more local workers than the machine has cores.
    batch : cases per dask task (default :func:`batch_size` of the pending cases and
        the workers).
    """
    from flexrv.design import load

    check_workers(n_workers, force)
    if batch is not None and (isinstance(batch, bool) or not isinstance(batch, int) or batch < 1):
        raise ConfigError(f"--batch {batch!r}: must be an integer >= 1 (cases per dask task)")
    out = Path(out_dir) if out_dir else Path("results") / spec.name
    # everything checked before any case runs: every case's design, task, options, outputs
    cases = build_cases(spec, validate=True)
    output_keys = known_outputs(spec, load(spec.preset))
    check_outputs(spec, output_keys)
    if scheduler:  # a dask scheduler answering its handshake? (before anything is written)
        check_scheduler(scheduler)
    out.mkdir(parents=True, exist_ok=True)
    spec_json = json.dumps(spec.__dict__, indent=1, default=str)
    spec_path = out / "spec.json"
    changed = spec_path.exists() and spec_path.read_text() != spec_json
    atomic_write_text(spec_path, spec_json)
    if changed or not (out / "table.csv").exists():
        # the table always matches spec.json: rebuilt now (pending cases marked "missing"),
        # so a rerun killed before its end never leaves the table of an older spec
        write_table(spec, cases, out, plots=False)
    todo = pending_cases(out, cases, retry_failed)
    cpu = CpuAccount()
    if todo:
        _execute(spec, todo, out, scheduler, n_workers, batch, progress, len(cases), cpu)
    csv_path, nc_path, plot_paths = write_table(spec, cases, out, plots=plots)
    total_failed = sum(json.loads(case_file(out, c).read_text()).get("status") != "ok" for c in cases)
    if output_keys is None:
        _check_outputs_after(spec, cases, out)
    return SweepSummary(
        out_dir=out,
        total=len(cases),
        computed=len(todo),
        skipped=len(cases) - len(todo),
        failed=total_failed,
        table_csv=csv_path,
        table_nc=nc_path,
        plots=plot_paths,
        cpu=cpu,
        case_ids=[c.case_id for c in cases],
    )


def _execute(
    spec: SweepSpec,
    todo: list[Case],
    out: Path,
    scheduler: str | None,
    n_workers: int | None,
    batch: int | None,
    progress: bool,
    total: int,
    cpu: CpuAccount,
) -> None:
    """Run the pending cases in batches on dask and store each batch's records as it
    arrives; ``cpu`` accounts the client's and the workers' CPU time."""
    import dask
    import distributed  # noqa: F401  (its config defaults exist before they are changed)

    with dask.config.set(DASK_CONFIG):
        _execute_batches(spec, todo, out, scheduler, n_workers, batch, progress, total, cpu)


def _execute_batches(spec, todo, out, scheduler, n_workers, batch, progress, total, cpu) -> None:
    from dask.distributed import Client, LocalCluster, as_completed

    cluster = None
    if scheduler:
        client = connect_scheduler(scheduler)
        workers = max(1, len(client.scheduler_info().get("workers", {})))
    else:
        workers = n_workers or os.cpu_count() or 1
        cluster = LocalCluster(
            n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None, silence_logs=40
        )
        client = Client(cluster)
    try:
        size = batch or batch_size(len(todo), workers)
        groups = [todo[i : i + size] for i in range(0, len(todo), size)]
        base = base_design(spec)
        cpu.start()
        futures = {
            client.submit(
                run_batch,
                base,
                [c.overrides for c in group],
                spec.task,
                spec.options,
                key=f"batch-{group[0].case_id}-{i}",
                pure=False,
            ): group
            for i, group in enumerate(groups)
        }
        with _progress(progress, total, total - len(todo)) as bar:
            task_id = bar.add_task(f"sweep {spec.name}", total=total, completed=total - len(todo))
            for future in as_completed(futures):
                group = futures[future]
                try:
                    records, worker_cpu = future.result()
                except Exception as exc:  # worker died
                    error = {"status": "failed", "error": f"worker error: {type(exc).__name__}: {exc}"}
                    records, worker_cpu = [dict(error) for _ in group], 0.0
                for case, record in zip(group, records):
                    _write_case(out, case, record)
                cpu.add_batch(worker_cpu, len(group))
                bar.advance(task_id, len(group))
        cpu.stop()
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def check_workers(n_workers, force: bool = False) -> None:
    """ConfigError naming --workers unless it is an integer >= 1 and, without ``force``,
    at most the machine's cores (more worker processes than cores only compete)."""
    if n_workers is None:
        return
    if isinstance(n_workers, bool) or not isinstance(n_workers, int) or n_workers < 1:
        raise ConfigError(f"--workers {n_workers!r}: must be an integer >= 1")
    cores = os.cpu_count() or 1
    if n_workers > cores and not force:
        raise ConfigError(
            f"--workers {n_workers}: this machine has {cores} cores; at most {cores} local workers "
            "(pass --force to start more)"
        )


#: address forms of a dask scheduler flexrv connects to
_ADDRESS_RE = re.compile(r"^(?:(tcp|tls)://)?\[?([^\]/]+?)\]?:(\d+)/?$")
#: largest first message of a dask scheduler's handshake [bytes] (its info dict, ~300 B)
_MAX_HANDSHAKE_BYTES = 1 << 20


def check_scheduler(address: str, timeout_s: float = 5.0) -> None:
    """ConfigError naming --scheduler within about ``timeout_s`` unless a dask scheduler
    answers at ``address``: the TCP connection must open, and (tcp://) the server must
    send the first frame of dask's handshake, an 8-byte length of at most 1 MiB followed
    by that many bytes. A server of another protocol (an HTTP server waits for a request,
    an SSH server sends a text banner) fails here instead of hanging the run or making
    dask allocate the length its banner spells."""
    import socket
    import struct

    m = _ADDRESS_RE.match(address.strip())
    if not m:
        raise ConfigError(f"--scheduler {address!r}: expected an address like tcp://127.0.0.1:8786")
    scheme, host, port = m.group(1) or "tcp", m.group(2), int(m.group(3))
    if port > 65535:
        raise ConfigError(f"--scheduler {address!r}: port {port} is not a TCP port (1-65535)")
    deadline = time.monotonic() + timeout_s

    def _recv(sock, n: int) -> bytes:
        data = b""
        while len(data) < n:
            sock.settimeout(max(deadline - time.monotonic(), 0.01))
            chunk = sock.recv(n - len(data))
            if not chunk:
                raise ValueError("it closed the connection during dask's handshake")
            data += chunk
        return data

    try:
        with socket.create_connection((host, port), timeout=timeout_s) as sock:
            if scheme == "tcp":
                (length,) = struct.unpack("<Q", _recv(sock, 8))
                if not 0 < length <= _MAX_HANDSHAKE_BYTES:
                    raise ValueError(f"its first message announces {length} bytes")
                _recv(sock, length)
    except socket.timeout:
        raise ConfigError(
            f"--scheduler {address}: the server at {host}:{port} accepted the connection but sent no dask "
            f"handshake within {timeout_s:g} s; it is not a dask scheduler"
        ) from None
    except ValueError as exc:
        raise ConfigError(
            f"--scheduler {address}: the server at {host}:{port} is not a dask scheduler ({exc})"
        ) from None
    except OSError as exc:
        raise ConfigError(
            f"--scheduler {address}: no dask scheduler reachable ({exc.strerror or type(exc).__name__}: {exc})"
        ) from None


def connect_scheduler(address: str, timeout_s: float = 5.0):
    """A dask Client of the scheduler at ``address`` (checked first by
    :func:`check_scheduler`); ConfigError within about ``timeout_s`` if it cannot be reached."""
    from dask.distributed import Client

    check_scheduler(address, timeout_s)
    try:
        return Client(address, timeout=timeout_s)
    except (OSError, TimeoutError, ValueError, TypeError) as exc:
        raise ConfigError(
            f"--scheduler {address}: cannot connect within {timeout_s:g} s "
            f"({type(exc).__name__}: {' '.join(str(exc).split())[:160]})"
        ) from None


def _check_outputs_after(spec: SweepSpec, cases: list[Case], out: Path) -> None:
    """Output keys of a task whose outputs are not declared: ConfigError naming a
    key that none of the successful cases produced (the table column is all NaN)."""
    results = []
    for c in cases:
        path = case_file(out, c)
        if path.exists():
            record = json.loads(path.read_text())
            if record.get("status") == "ok":
                results.append(record.get("result", {}))
    if not results:
        return
    keys = set().union(*(_dotted_keys(r) for r in results))
    check_outputs(spec, keys)


def _progress(enabled: bool, total: int, done: int):
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    return Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        disable=not enabled,
        transient=False,
        refresh_per_second=2,
    )


def _as_float(value: Any) -> float:
    if isinstance(value, bool):
        return float(value)
    if isinstance(value, (int, float)):
        return float(value)
    return math.nan


def write_table(spec: SweepSpec, cases: list[Case], out: Path, plots: bool = True) -> tuple[Path, Path, list[Path]]:
    """Collect all stored case results into ``table.csv``, ``table.nc`` and (``plots``) PNGs."""
    import numpy as np
    import xarray as xr

    from flexrv.cache import atomic_path

    params = sorted({k for c in cases for k in c.overrides})
    rows = []
    for case in cases:
        path = case_file(out, case)
        record = json.loads(path.read_text()) if path.exists() else {"status": "missing"}
        row = {
            "case_id": case.case_id,
            "status": record.get("status", "missing"),
            "error": record.get("error", ""),
            "wall_time_s": record.get("wall_time_s", math.nan),
        }
        for p in params:
            row[p] = case.overrides.get(p, math.nan)
        result = record.get("result", {})
        for o in spec.outputs:
            row[o] = _as_float(pick(result, o)) if result else math.nan
        rows.append(row)
    columns = ["case_id", "status", *params, *spec.outputs, "wall_time_s", "error"]
    csv_path = out / "table.csv"
    lines = [",".join(columns)]
    for row in rows:
        lines.append(",".join(json.dumps(row[c]) if isinstance(row[c], str) else repr(row[c]) for c in columns))
    atomic_write_text(csv_path, "\n".join(lines) + "\n")

    data_vars = {}
    for c in [*params, *spec.outputs, "wall_time_s"]:
        values = [_as_float(r[c]) for r in rows]
        data_vars[c.replace("/", "_")] = ("case", np.asarray(values, dtype=float))
    data_vars["status"] = ("case", np.asarray([r["status"] for r in rows], dtype=str))
    data_vars["error"] = ("case", np.asarray([r["error"] for r in rows], dtype=str))
    ds = xr.Dataset(
        data_vars,
        coords={"case": [r["case_id"] for r in rows]},
        attrs={"sweep": spec.name, "preset": spec.preset, "task": spec.task},
    )
    nc_path = out / "table.nc"
    with atomic_path(nc_path) as tmp:
        ds.to_netcdf(tmp, engine="h5netcdf")
    return csv_path, nc_path, (_plot_table(spec, rows, params, out) if plots else [])


def _plot_table(spec: SweepSpec, rows: list[dict], params: list[str], out: Path) -> list[Path]:
    """One PNG per output: vs the first varied parameter, one line per value of the
    others."""
    if not params or not spec.outputs:
        return []
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from flexrv.cache import atomic_path

    ok = [r for r in rows if r["status"] == "ok"]
    x_key = params[0]
    others = params[1:]
    paths = []
    for output in spec.outputs:
        fig, ax = plt.subplots(figsize=(6, 4))
        groups: dict[tuple, list[dict]] = {}
        for r in ok:
            groups.setdefault(tuple(r[o] for o in others), []).append(r)
        for key, members in sorted(groups.items(), key=lambda kv: str(kv[0])):
            members = sorted(members, key=lambda r: _as_float(r[x_key]))
            label = ", ".join(f"{o}={v}" for o, v in zip(others, key)) or None
            ax.plot([_as_float(r[x_key]) for r in members], [r[output] for r in members], "o-", label=label)
        ax.set_xlabel(x_key)
        ax.set_ylabel(output)
        ax.set_title(f"{spec.name}: {output}")
        if others:
            ax.legend(fontsize=7)
        ax.grid(True, alpha=0.3)
        fig.tight_layout()
        path = out / f"sweep_{output.replace('.', '_').replace('/', '_')}.png"
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=110, format="png")
        plt.close(fig)
        paths.append(path)
    return paths
