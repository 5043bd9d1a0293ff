"""What an optimisation asks of a run: objectives (`--minimize EXPR`, `--maximize EXPR`) and constraints
(`--constraint "EXPR<=VALUE"`), expressions over the run's summary values and history columns, checked against the
base scene before anything runs and evaluated on a run's record (its summary and history, plain data).

    goals = Goals.parse(scene, minimize=["at(chamber.pressure, tip_rotation, -90)"], constraints=["max_stretch<=2.5"])
    goals.evaluate({"summary": result.summary(), "history": result.history})   # -> Scores

An expression is arithmetic (+ - * / **, unary -, numbers, abs(x), sqrt(x)) on

- a summary value by its dotted path: max_stretch, tip_rotation_deg, peak_pressure, blocked_force,
  chambers.<chamber>.final_pressure, extremes.tip_rotation.min, ...;
- a history column by name: its final value (tip_rotation, chamber.pressure, max_stretch, ...; a name that is both is
  the summary's value);
- final(C), min(C), max(C): the last, least or largest value of history column C over the run;
- at(Y, X, v): the value of column Y where column X first reaches v, linearly interpolated between the two steps
  around it (at(chamber.pressure, tip_rotation, -90): the pressure at which the tip has turned through -90 degrees;
  a run in which X never reaches v has no value: the optimiser records the design as infeasible, short by
  min |X - v|, so that its sampler learns how far it fell short);
- rms(C, v): sqrt(mean((C - v)^2)) over the steps after rest: how far a column stays from a target value, or, v a
  list [v1, v2, ...] of one value per step after rest, from a target trajectory (rms(tip_dy, [-0.1, -0.2, -0.3]); a
  run with another number of steps has no value).

A constraint `A<=B` (or `A>=B`) holds when its violation A - B (B - A) is <= 0; Optuna's samplers take the violation.
"""

from __future__ import annotations

import ast
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import PneumaInputError, require
from ..solve.columns import COLUMNS, history_dimensions
from ..solve.records import SOLVER_COLUMNS

MAX_EXPRESSION = 500  # characters of an objective or constraint
# the summary's numeric values (Result.summary) by their first key; chambers.<name>.<field> and
# extremes.<column>.<field> below
SUMMARY_NUMBERS = (
    "vertices",
    "triangles",
    "tetrahedra",
    "element_order",
    "tip_deflection",
    "tip_dz",
    "tip_rotation_deg",
    "tip_twist_deg",
    "blocked_force",
    "peak_pressure",
    "contact_fz",
    "max_stretch",
    "max_stretch_step",
    "max_stretch_limit",
    "max_residual",
    "min_det_F",
    "newton_iterations_total",
    "newton_iterations_max",
    "increment_cuts",
    "wall_seconds",
    "solve_seconds_per_step",
    "steps",
)
CHAMBER_FIELDS = ("rest_area", "final_area", "area_ratio", "final_pressure", "peak_pressure")
EXTREME_FIELDS = ("min", "max", "min_step", "max_step")
COLUMN_FUNCTIONS = {"final": 1, "min": 1, "max": 1, "at": 3, "rms": 2}  # their arguments: columns first, then numbers
MATH: dict[str, Callable[[float], float]] = {"abs": abs, "sqrt": math.sqrt}
OPERATORS: dict[type, Callable] = {
    ast.Add: lambda a, b: a + b,
    ast.Sub: lambda a, b: a - b,
    ast.Mult: lambda a, b: a * b,
    ast.Div: lambda a, b: a / b,
    ast.Pow: lambda a, b: a**b,
}
COLUMN_ARGUMENTS = {"final": 1, "min": 1, "max": 1, "at": 2, "rms": 1}  # how many leading arguments are columns


class NoValue(Exception):
    """The run has no value for an expression (a column that never reaches the level at() asks for, a summary value
    this run lacks). shortfall: for at(), how far the column stayed from the level (min |X - v| over the run), which
    the optimiser tells the sampler as the violation of a design that fell short; None otherwise."""

    def __init__(self, message: str, shortfall: float | None = None):
        super().__init__(message)
        self.shortfall = shortfall


def dotted_name(node: ast.expr) -> str | None:
    """a.b.c of a chain of attributes on a name, else None."""
    parts = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    if not isinstance(node, ast.Name):
        return None
    return ".".join([node.id, *reversed(parts)])


def crossing(y: np.ndarray, x: np.ndarray, level: float) -> float | None:
    """y where x first reaches level (x[i] on the far side of level from x[0], or at it), linearly interpolated
    between steps i - 1 and i; None where it never does."""
    side = np.sign(x - level)
    reached = np.nonzero((side == 0) | (side != side[0]))[0]
    if side[0] == 0:
        return float(y[0])
    if not len(reached):
        return None
    i = int(reached[0])
    t = (level - x[i - 1]) / (x[i] - x[i - 1])
    return float(y[i - 1] + t * (y[i] - y[i - 1]))


@dataclass(frozen=True)
class Expression:
    """One checked expression (its text and its syntax tree)."""

    text: str
    tree: ast.expr

    def value(self, record: dict) -> float:
        """The expression on a run's record {"summary": dict, "history": {column: values}} (NoValue: none)."""
        value = float(self._value(self.tree, record))
        if not math.isfinite(value):
            raise NoValue(f"{self.text} is {value}")
        return value

    def _value(self, node: ast.expr, record: dict) -> float:
        if isinstance(node, ast.Constant):
            assert isinstance(node.value, (int, float))  # (Checker.check)
            return float(node.value)
        if isinstance(node, ast.UnaryOp):
            operand = self._value(node.operand, record)
            return -operand if isinstance(node.op, ast.USub) else operand
        if isinstance(node, ast.BinOp):
            try:
                return OPERATORS[type(node.op)](self._value(node.left, record), self._value(node.right, record))
            except (ZeroDivisionError, OverflowError) as exc:
                raise NoValue(f"{self.text}: {exc}") from None
        if isinstance(node, ast.Call):
            assert isinstance(node.func, ast.Name)
            name = node.func.id
            if name in MATH:
                try:
                    return MATH[name](self._value(node.args[0], record))
                except ValueError as exc:
                    raise NoValue(f"{self.text}: {exc}") from None
            columns = [column_of(record, dotted_name(a) or "") for a in node.args[: COLUMN_ARGUMENTS[name]]]
            numbers = [
                np.array([self._value(e, record) for e in a.elts])
                if isinstance(a, ast.List)
                else self._value(a, record)
                for a in node.args[COLUMN_ARGUMENTS[name] :]
            ]
            return column_function(name, columns, numbers, self.text)
        key = dotted_name(node)
        assert key is not None
        found = summary_value(record["summary"], key)
        if found is not None:
            return found
        if key in record["history"]:
            return float(np.asarray(record["history"][key])[-1])
        raise NoValue(f"{self.text}: this run has no value {key}")


def column_of(record: dict, name: str) -> np.ndarray:
    if name not in record["history"]:
        raise NoValue(f"this run's history has no column {name}")
    return np.asarray(record["history"][name], dtype=float)


def column_function(name: str, columns: list[np.ndarray], numbers: list, text: str) -> float:
    if name == "final":
        return float(columns[0][-1])
    if name in ("min", "max"):
        return float(getattr(np, name)(columns[0]))
    if name == "rms":
        after_rest = columns[0][1:] if len(columns[0]) > 1 else columns[0]
        target = np.asarray(numbers[0])
        if target.ndim and len(target) != len(after_rest):
            raise NoValue(
                f"{text}: the trajectory has {len(target)} values, the run {len(after_rest)} steps after rest"
            )
        return float(np.sqrt(np.mean((after_rest - target) ** 2)))
    found = crossing(columns[0], columns[1], numbers[0])
    if found is None:
        shortfall = float(np.min(np.abs(columns[1] - numbers[0])))
        raise NoValue(f"{text}: the run never reaches {numbers[0]:g} (it comes within {shortfall:.4g})", shortfall)
    return found


def summary_value(summary: dict, name: str) -> float | None:
    node = summary
    for part in name.split("."):
        if not isinstance(node, dict) or part not in node:
            return None
        node = node[part]
    return float(node) if isinstance(node, (int, float)) and not isinstance(node, bool) else None


class Checker:
    """The names a scene's runs have: its history columns and its summary's numeric values (SUMMARY_NUMBERS,
    chambers.<chamber>.<CHAMBER_FIELDS>, extremes.<column>.<EXTREME_FIELDS>)."""

    def __init__(self, scene):
        obstacles = [o.name for o in scene.obstacles]
        self.columns = set(history_dimensions(scene, obstacles, scene.dim)) | set(SOLVER_COLUMNS)
        self.columns |= {column.name for column in COLUMNS}  # (history_dimensions leaves out the pure numbers)
        self.columns |= {f"{name}.area_ratio" for name in scene.chamber_names}
        self.chambers = set(scene.chamber_names)

    def is_summary(self, name: str) -> bool:
        parts = name.split(".")
        if len(parts) == 1:
            return name in SUMMARY_NUMBERS
        if parts[0] == "chambers":
            return len(parts) == 3 and parts[1] in self.chambers and parts[2] in CHAMBER_FIELDS
        if parts[0] == "extremes":
            return len(parts) >= 3 and ".".join(parts[1:-1]) in self.columns and parts[-1] in EXTREME_FIELDS
        return False

    def unknown(self, name: str, column: bool) -> str:
        known = sorted(self.columns) if column else [*SUMMARY_NUMBERS, "chambers.<chamber>.<field>", "extremes.<...>"]
        what = "a history column" if column else "a summary value or a history column"
        return f"{name!r} is not {what} of this scene; those are: {', '.join(known)}"

    def check(self, node: ast.expr, where: str) -> None:
        """Refuse (one PneumaInputError naming `where`) what an expression may not hold."""
        if isinstance(node, ast.Constant):
            require(
                isinstance(node.value, (int, float)) and not isinstance(node.value, bool),
                f"{where}: {node.value!r} is not a number",
            )
        elif isinstance(node, ast.UnaryOp):
            require(isinstance(node.op, (ast.USub, ast.UAdd)), f"{where}: only - and + stand before a value")
            self.check(node.operand, where)
        elif isinstance(node, ast.BinOp):
            require(type(node.op) in OPERATORS, f"{where}: the operators are + - * / **")
            self.check(node.left, where)
            self.check(node.right, where)
        elif isinstance(node, ast.Call):
            self.check_call(node, where)
        else:
            name = dotted_name(node)
            require(name is not None, f"{where}: {ast.unparse(node)!r} is not a number, a name or a function call")
            assert name is not None
            require(self.is_summary(name) or name in self.columns, f"{where}: {self.unknown(name, False)}")

    def check_call(self, node: ast.Call, where: str) -> None:
        name = node.func.id if isinstance(node.func, ast.Name) else None
        allowed = ", ".join([*MATH, *COLUMN_FUNCTIONS])
        require(name in MATH or name in COLUMN_FUNCTIONS, f"{where}: the functions are {allowed}")
        assert name is not None
        wanted = 1 if name in MATH else COLUMN_FUNCTIONS[name]
        require(
            len(node.args) == wanted and not node.keywords,
            f"{where}: {name}() takes {wanted} argument{'s' if wanted > 1 else ''}",
        )
        columns = 0 if name in MATH else COLUMN_ARGUMENTS[name]
        for argument in node.args[:columns]:
            column = dotted_name(argument)
            require(column in self.columns, f"{where}: {self.unknown(column or ast.unparse(argument), True)}")
        for argument in node.args[columns:]:
            if name == "rms" and isinstance(argument, ast.List):  # a trajectory: a number per step after rest
                require(argument.elts, f"{where}: rms()'s trajectory is a list of one number or more")
                for item in argument.elts:
                    self.check(item, where)
                continue
            self.check(argument, where)

    def expression(self, text: str, where: str) -> Expression:
        require(
            isinstance(text, str) and 0 < len(text.strip()) <= MAX_EXPRESSION,
            f"{where}: an expression of 1 to {MAX_EXPRESSION} characters",
        )
        try:
            tree = ast.parse(text.strip(), mode="eval").body
        except SyntaxError:
            raise PneumaInputError(f"{where} {text!r} does not parse as an expression") from None
        self.check(tree, f"{where} {text!r}")
        return Expression(text.strip(), tree)


@dataclass(frozen=True)
class Constraint:
    """left <= right (upper) or left >= right: violation() <= 0 where it holds."""

    text: str
    left: Expression
    right: Expression
    upper: bool

    def violation(self, record: dict) -> float:
        difference = self.left.value(record) - self.right.value(record)
        return difference if self.upper else -difference


@dataclass(frozen=True)
class Goals:
    """Objectives (expressions, each with its direction, "minimize" or "maximize") and constraints."""

    objectives: tuple[Expression, ...]
    directions: tuple[str, ...]
    constraints: tuple[Constraint, ...] = ()

    @classmethod
    def parse(cls, scene, objectives: Sequence[tuple[str, str]], constraints: Sequence[str] = ()) -> Goals:
        """objectives: (direction, expression) pairs in order; constraints: "A<=B" or "A>=B" texts."""
        require(1 <= len(objectives) <= 2, "an optimisation has one or two objectives (--minimize, --maximize)")
        for direction, _ in objectives:
            require(direction in ("minimize", "maximize"), f"{direction!r}: an objective is minimize or maximize")
        checker = Checker(scene)
        expressions = tuple(checker.expression(text, f"--{d}") for d, text in objectives)
        return cls(
            expressions, tuple(d for d, _ in objectives), tuple(parse_constraint(checker, t) for t in constraints)
        )

    @property
    def texts(self) -> list[str]:
        return [e.text for e in self.objectives]

    def evaluate(self, record: dict) -> tuple[list[float], list[float]]:
        """The objectives' values and the constraints' violations on a run's record (NoValue: one has none)."""
        return [e.value(record) for e in self.objectives], [c.violation(record) for c in self.constraints]


def parse_constraint(checker: Checker, text: str) -> Constraint:
    where = f"--constraint {text!r}"
    require(isinstance(text, str) and len(text) <= MAX_EXPRESSION, f"{where}: at most {MAX_EXPRESSION} characters")
    try:
        tree = ast.parse(text.strip(), mode="eval").body
    except SyntaxError:
        raise PneumaInputError(f"{where} does not parse: write EXPR<=VALUE or EXPR>=VALUE") from None
    require(
        isinstance(tree, ast.Compare)
        and len(tree.ops) == 1
        and isinstance(tree.ops[0], (ast.LtE, ast.GtE, ast.Lt, ast.Gt)),
        f"{where}: a constraint is EXPR<=VALUE or EXPR>=VALUE",
    )
    assert isinstance(tree, ast.Compare)
    sides = []
    for node in (tree.left, tree.comparators[0]):
        checker.check(node, where)
        sides.append(Expression(ast.unparse(node), node))
    return Constraint(text.strip(), sides[0], sides[1], isinstance(tree.ops[0], (ast.LtE, ast.Lt)))
