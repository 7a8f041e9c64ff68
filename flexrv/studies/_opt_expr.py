"""Names, objectives, constraints and design variables of ``flexrv optimize``
(:mod:`flexrv.studies.optimize`): parsing and checking of the user's text.

Metric names are ``<quantity>_<stat>_<unit>`` (``lost_motion_p95_arcmin``,
``rigidity_median_Nm_per_arcmin``) with the stats of :data:`STATS`, and
``<name>_yield`` for the fraction of builds meeting a rule (``no_preload_yield``,
``spec_yield``). A constraint is an inequality between arithmetic expressions of metric
names and numbers, parsed with :mod:`ast` and evaluated node by node: only names,
numbers, ``+ - * /``, unary minus and one comparison ``<= >= < >`` are accepted, so no
text given on the command line is ever executed.
"""

from __future__ import annotations

import ast
import math
import re
from dataclasses import dataclass

from flexrv.errors import InputError

#: statistics of a quantity over the batch (the key of
#: :func:`flexrv.studies.tolerance.percentiles` they read, or ``nominal``: the design
#: without tolerance draws)
STATS = {
    "p50": "P50",
    "median": "P50",
    "p95": "P95",
    "p997": "P99.7",
    "mean": "mean",
    "std": "std",
    "min": "min",
    "max": "max",
    "nominal": None,
}


def metric_name(quantity: str, stat: str, unit: str) -> str:
    """``lost_motion`` + ``p95`` + ``arcmin`` -> ``lost_motion_p95_arcmin`` (no unit: no suffix)."""
    return f"{quantity}_{stat}_{unit}" if unit else f"{quantity}_{stat}"


def metric_names(quantities: dict[str, str], yields: list[str]) -> list[str]:
    """Every metric of a problem: the stats of every quantity, the yields, ``failed_fraction``."""
    names = [metric_name(q, s, u) for q, u in quantities.items() for s in STATS]
    return names + [f"{y}_yield" for y in yields] + ["failed_fraction"]


def _close(text: str, names: list[str]) -> str:
    import difflib

    near = difflib.get_close_matches(text, names, n=3, cutoff=0.5)
    return f"; did you mean {', '.join(near)}?" if near else ""


# ----------------------------------------------------------------------------- objectives
@dataclass(frozen=True)
class Objective:
    """A metric to minimise or maximise."""

    name: str
    sense: str  #: "min" or "max"

    def value_to_min(self, v: float) -> float:
        """The value in minimisation form (negated for ``max``)."""
        return v if self.sense == "min" else -v

    def __str__(self) -> str:
        return f"{self.name}:{self.sense}"


def parse_objective(text: str, names: list[str]) -> Objective:
    """``"lost_motion_p95_arcmin:min"`` -> Objective (sense ``min`` by default)."""
    m = re.match(r"^\s*([A-Za-z_][A-Za-z0-9_]*)\s*(?::\s*(min|max))?\s*$", str(text))
    if not m:
        raise InputError(f"--objective {text!r}: bad syntax; write NAME[:min|max], e.g. lost_motion_p95_arcmin:min")
    name, sense = m.group(1), m.group(2) or "min"
    if name not in names:
        raise InputError(
            f"--objective {text!r}: unknown metric {name!r}{_close(name, names)} "
            f"(metrics are <quantity>_<stat>_<unit>, stats {', '.join(STATS)}; allowed: {', '.join(names)})"
        )
    return Objective(name, sense)


# ----------------------------------------------------------------------------- expressions
_BINOPS = {ast.Add: lambda a, b: a + b, ast.Sub: lambda a, b: a - b, ast.Mult: lambda a, b: a * b}
_CMP = {ast.LtE: "<=", ast.Lt: "<", ast.GtE: ">=", ast.Gt: ">"}


def _check_node(node: ast.AST, names: list[str], text: str, option: str) -> set[str]:
    """Names used by an arithmetic expression; InputError for anything else."""
    if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) and not isinstance(node.value, bool):
        if not math.isfinite(node.value):
            raise InputError(f"{option} {text!r}: numbers must be finite")
        return set()
    if isinstance(node, ast.Name):
        if node.id not in names:
            raise InputError(f"{option} {text!r}: unknown metric {node.id!r}{_close(node.id, names)}")
        return {node.id}
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        return _check_node(node.operand, names, text, option)
    if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Add, ast.Sub, ast.Mult, ast.Div)):
        return _check_node(node.left, names, text, option) | _check_node(node.right, names, text, option)
    raise InputError(
        f"{option} {text!r}: {type(node).__name__} is not allowed; use metric names, numbers, + - * / and one of "
        "<= >= < >"
    )


def _value(node: ast.AST, values: dict[str, float]) -> float:
    if isinstance(node, ast.Constant):
        return float(node.value)
    if isinstance(node, ast.Name):
        return float(values[node.id])
    if isinstance(node, ast.UnaryOp):
        v = _value(node.operand, values)
        return -v if isinstance(node.op, ast.USub) else v
    a, b = _value(node.left, values), _value(node.right, values)
    if isinstance(node.op, ast.Div):
        return a / b if b != 0 else math.copysign(math.inf, a) if a else math.nan
    return _BINOPS[type(node.op)](a, b)


@dataclass(frozen=True)
class Constraint:
    """``lhs <op> rhs`` over metrics; :meth:`violation` <= 0 where it holds."""

    text: str
    lhs: ast.AST
    op: str
    rhs: ast.AST
    names: frozenset

    def violation(self, values: dict[str, float]) -> float:
        """(lhs - rhs) for <=, (rhs - lhs) for >=, relative to max(|rhs|, |lhs|, 1e-12) when the
        other side is a number; NaN metrics give +inf."""
        a, b = _value(self.lhs, values), _value(self.rhs, values)
        if not (math.isfinite(a) and math.isfinite(b)):
            return math.inf
        g = a - b if self.op in ("<=", "<") else b - a
        if self.op in ("<", ">") and g == 0.0:
            g = 1e-12
        return g / max(abs(a), abs(b), 1e-12)

    def holds(self, values: dict[str, float]) -> bool:
        return self.violation(values) <= 0.0

    def __str__(self) -> str:
        return self.text


def parse_constraint(text: str, names: list[str], option: str = "--constraint") -> Constraint:
    """Parse ``"pin_contact_pressure_p95_MPa <= 1500"`` (see module docstring)."""
    src = str(text).strip()
    try:
        tree = ast.parse(src, mode="eval")
    except SyntaxError:
        raise InputError(f'{option} {text!r}: not an expression; write e.g. "lost_motion_p95_arcmin <= 1"') from None
    node = tree.body
    if not isinstance(node, ast.Compare) or len(node.ops) != 1 or type(node.ops[0]) not in _CMP:
        raise InputError(f"{option} {text!r}: must be one comparison LHS <= RHS (or >=, <, >)")
    used = _check_node(node.left, names, text, option) | _check_node(node.comparators[0], names, text, option)
    if not used:
        raise InputError(f"{option} {text!r}: names no metric (allowed: {', '.join(names)})")
    return Constraint(src, node.left, _CMP[type(node.ops[0])], node.comparators[0], frozenset(used))


# ----------------------------------------------------------------------------- specs
@dataclass(frozen=True)
class BuildRule:
    """A per-build rule ``quantity <op> value`` (a spec of the yield)."""

    quantity: str
    op: str
    value: float
    label: str

    def ok(self, y):
        import numpy as np

        y = np.asarray(y, dtype=float)
        with np.errstate(invalid="ignore"):
            return {"<=": y <= self.value, ">=": y >= self.value, "<": y < self.value, ">": y > self.value}[self.op]


def parse_spec(text: str, quantities: dict[str, str]) -> BuildRule:
    """``"lost_motion_arcmin <= 1"`` -> BuildRule on the build quantity ``lost_motion``."""
    allowed = {f"{q}_{u}" if u else q: q for q, u in quantities.items()}
    m = re.match(r"^\s*([A-Za-z_][A-Za-z0-9_]*)\s*(<=|>=|<|>)\s*([-+0-9.eE]+)\s*$", str(text))
    if not m:
        raise InputError(
            f"--spec {text!r}: bad syntax; write QUANTITY<=VALUE (or >=, <, >), e.g. lost_motion_arcmin<=1"
        )
    name, op, val = m.groups()
    if name not in allowed:
        raise InputError(f"--spec {text!r}: unknown quantity {name!r}; allowed: {', '.join(allowed)}")
    try:
        v = float(val)
    except ValueError:
        raise InputError(f"--spec {text!r}: limit {val!r} is not a number") from None
    return BuildRule(allowed[name], op, v, f"{name}{op}{v:g}")


# ----------------------------------------------------------------------------- variables
@dataclass(frozen=True)
class Variable:
    """A design field varied over [lo, hi] (dotted path into the design table)."""

    path: str
    lo: float
    hi: float
    integer: bool = False

    def value(self, x: float):
        return int(round(x)) if self.integer else float(x)


def parse_vary(text: str, base: dict) -> Variable:
    """``"second_stage.modification_equidistant_mm=0:0.015"`` -> Variable; the field must be a
    number of the design (InputError naming it otherwise, and for LO >= HI)."""
    m = re.match(r"^\s*([A-Za-z_][A-Za-z0-9_.]*)\s*=\s*([^:]+):([^:]+)$", str(text))
    if not m:
        raise InputError(
            f"--vary {text!r}: bad syntax; write FIELD=LO:HI, e.g. second_stage.modification_shift_mm=-0.01:0.01"
        )
    path, lo_s, hi_s = m.group(1), m.group(2).strip(), m.group(3).strip()
    node = base
    for key in path.split("."):
        if not isinstance(node, dict) or key not in node:
            where = sorted(node) if isinstance(node, dict) else []
            raise InputError(
                f"--vary {text!r}: unknown design field {path!r} (no {key!r}{_close(key, where)}; "
                f"fields here: {', '.join(where) if where else 'none'})"
            )
        node = node[key]
    if isinstance(node, bool) or not isinstance(node, (int, float)):
        raise InputError(f"--vary {text!r}: {path} is {type(node).__name__} {node!r}, not a number")
    try:
        lo, hi = float(lo_s), float(hi_s)
    except ValueError:
        raise InputError(f"--vary {text!r}: LO {lo_s!r} and HI {hi_s!r} must be numbers") from None
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise InputError(f"--vary {text!r}: LO and HI must be finite")
    if lo >= hi:
        raise InputError(f"--vary {text!r}: LO = {lo:g} must be below HI = {hi:g}")
    return Variable(path, lo, hi, integer=isinstance(node, int))
