"""The artefact registry: every table and figure, declared beside the function that makes it.

An *artefact* is one computation of a study (a paper, or a study beyond the papers): the function
``make(config, outdir) -> list[Path]``, the files it writes, the artefacts it needs, the config
sections it reads and the tolerance within which a rerun on another machine must agree with the
committed record. It is declared with :func:`artefact` on the function itself::

    @artefact("zhao2017_3p4s", "table1", outputs=["table1.csv", "table1.md"],
              config=["zhao2017_3p4s.table1"], tolerance=ROUNDING)
    def table1(config, outdir): ...

Snakemake's rules (``workflow/rules/artefacts.smk``), ``rule all``, the reproduction check,
``parakin which`` and the tests all take their lists from here. This module imports no study:
:func:`load` imports the study modules named in the config's ``studies`` list, whose decorators
fill :data:`REGISTRY`.
"""

from __future__ import annotations

import ast
import importlib
import inspect
import pkgutil
import re
import sys
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from functools import cache, partial, wraps
from pathlib import Path
from typing import Any

__all__ = [
    "Tolerance",
    "ConditionNumber",
    "Artefact",
    "artefact",
    "figure",
    "drawn_figure",
    "drawn_figures",
    "table",
    "table_files",
    "REGISTRY",
    "load",
    "of_module",
    "import_study",
    "find",
    "which",
    "prune_config",
    "Job",
    "jobs",
    "EXACT",
    "ROUNDING",
    "ITERATIVE",
    "DESCRIPTIVE",
    "TIMING",
]


@dataclass(frozen=True)
class ConditionNumber:
    """A column limit for condition numbers of ``n x n`` (or smaller) matrices formed and
    decomposed in double precision, where round-off is all there is to compare near a singularity.

    Forming ``J`` rounds each entry (``|E|_2 <= sqrt(n) eps |J|_2``) and a backward-stable SVD adds
    ``n eps |J|_2``, so the computed smallest singular value is off by at most ``k sigma_max`` with
    ``k = (n + sqrt(n)) eps``: ``kappa`` is off by the relative amount ``k kappa / (1 - k kappa)``.
    Two values agree when both are *singular to working precision* (``k kappa >= 1/2``: the smallest
    singular value is within a factor two of the round-off) or when they differ by at most the sum
    of both bounds, ``2 k kappa / (1 - k kappa)`` with the larger ``kappa`` (relative): the class of
    a singular matrix is compared, never its round-off digits. Declared with issue 28, after a
    fresh run on another CPU moved Ye's singular home pose from 2.840e17 to 2.830e17.
    """

    n: int

    def __post_init__(self):
        if not (isinstance(self.n, int) and self.n >= 1):
            raise ValueError(f"ConditionNumber n = {self.n!r} must be an integer >= 1")

    @property
    def k(self) -> float:
        return (self.n + self.n**0.5) * 2.220446049250313e-16

    def agree(self, record, run):
        """Element-wise agreement of two arrays of condition numbers (``inf``: exactly singular)."""
        import numpy as np

        a = np.abs(np.asarray(record, dtype=float))
        b = np.abs(np.asarray(run, dtype=float))
        big = np.fmax(a, b)
        with np.errstate(invalid="ignore", over="ignore"):
            singular = (self.k * a >= 0.5) & (self.k * b >= 0.5)
            allowed = 2 * self.k * big / (1 - self.k * big)
            close = (self.k * big < 0.5) & (np.abs(a - b) <= allowed * big + 1e-300)
        return singular | close | (np.isnan(a) & np.isnan(b))


@dataclass(frozen=True)
class Tolerance:
    """How closely a rerun must agree with the committed record, and why.

    Numeric table cells agree when ``|ours - record| <= atol + rtol * |record|``; columns named in
    ``columns`` get their own ``(rtol, atol)`` (for ``kind="statistical"`` only they are compared:
    a chaotic computation lists what is stable) or a :class:`ConditionNumber` (condition numbers,
    compared by class near a singularity: :meth:`condition`); columns in ``skip`` are not compared
    (a chaotic trajectory, a round-off residual), each reason stated in ``reason``. Timing columns
    (:func:`parakin.io.is_timing_column`) are never compared and never decide anything.
    ``files`` names output files that are not compared at all (e.g. one seed's trajectory of a
    genetic algorithm), and ``rows`` keeps, for every CSV, only the rows where the given column
    has one of the given values (e.g. the final generation). ``intervals``: pairs of columns
    ``(low, high)`` holding a confidence interval (of the median over independent runs of a chaotic
    computation); a rerun agrees when its interval overlaps the record's (for two 99 % intervals of
    one distribution, apart by chance about 3 times in 10^4). ``over_successes`` maps a column
    holding a statistic over the successful trials of its row only (the median iterations of the
    converged solves) to ``(fraction, trials)``, the columns of the success fraction and the number
    of trials: the fraction's own tolerance lets ``(atol + rtol |fraction|) trials`` successes
    differ between runs, and a median is fixed only while fewer than half its sample may change
    (its breakdown point is 1/2), so the statistic is compared only in rows where both runs have
    more than twice that many successes (:meth:`comparable_successes`).
    """

    kind: str
    rtol: float
    atol: float
    reason: str
    columns: dict[str, tuple[float, float]] = field(default_factory=dict)
    skip: tuple[str, ...] = ()
    files: tuple[str, ...] = ()
    rows: tuple[str, tuple] | None = None
    intervals: tuple[tuple[str, str], ...] = ()
    over_successes: dict[str, tuple[str, str]] = field(default_factory=dict)

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"tolerance kind {self.kind!r} must be one of {KINDS}")
        if not (self.rtol >= 0 and self.atol >= 0):
            raise ValueError(f"tolerance rtol = {self.rtol}, atol = {self.atol} must be >= 0")
        if not self.reason.strip():
            raise ValueError("a tolerance needs its reason")

    def limits(self, column: str) -> tuple[float, float] | ConditionNumber:
        """``(rtol, atol)`` of one column, or its :class:`ConditionNumber` rule."""
        return self.columns.get(column, (self.rtol, self.atol))

    def comparable_successes(self, column: str, record, run):
        """The rows (a boolean array) of the tables ``record`` and ``run`` where ``column``, a
        statistic over each row's successes (``over_successes``), is compared: both runs have more
        than twice the successes the fraction's tolerance lets differ."""
        import numpy as np

        fraction, trials = self.over_successes[column]
        rtol, atol = self.limits(fraction)
        p0, p1 = record[fraction].to_numpy(float), run[fraction].to_numpy(float)
        n = record[trials].to_numpy(float)
        may_differ = (atol + rtol * np.abs(p0)) * n
        return (p0 * n > 2 * may_differ) & (p1 * n > 2 * may_differ)

    @staticmethod
    def condition(n: int) -> ConditionNumber:
        """The column limit of condition numbers of matrices up to ``n x n`` (:class:`ConditionNumber`)."""
        return ConditionNumber(n)

    @staticmethod
    def exactly(*columns: str) -> dict[str, tuple[float, float]]:
        """Column limits ``(rtol, atol) = (0, 0)`` of ``columns``: counts and other properties of
        the input that a rerun must give exactly."""
        return dict.fromkeys(columns, (0.0, 0.0))

    @classmethod
    def statistical(cls, reason: str, **fields) -> Tolerance:
        """A ``kind="statistical"`` tolerance: only what ``fields`` (``columns``, ``intervals``,
        ...) name is compared, so the default ``rtol`` and ``atol`` are 0."""
        return cls("statistical", 0.0, 0.0, reason, **fields)

    def but(self, reason: str | None = None, **changes) -> Tolerance:
        """A copy with some fields changed (and a reason that says why)."""
        from dataclasses import replace

        return replace(self, reason=reason or self.reason, **changes)


#: exact: closed forms and symbolic results; only floating-point summation order may differ
#: statistical: stochastic or chaotic computations (GA, PSO, network training): only what is
#:   stable across BLAS kernels and thread counts is compared, with a margin
#: descriptive: drawings and set-up echoes (nothing computed that could drift beyond rounding)
KINDS = ("exact", "rounding", "iterative", "statistical", "descriptive", "timing")

#: closed forms, linear algebra of fixed size, symbolic counts: BLAS kernels change the
#: summation order, so agreement to ~1e3 ulp of the largest value, never bit for bit
EXACT = Tolerance(
    "exact", 1e-9, 1e-12, "closed form: only the floating-point summation order differs"
)
#: iterative solves converged to 1e-10 or better, quadratures, fits converged to 1e-14
ROUNDING = Tolerance(
    "rounding",
    1e-6,
    1e-9,
    "iterative solve or fit converged far below this; a BLAS kernel moves the last "
    "iterate by rounding only",
)
#: iteration counts and success rates of iterative solvers: a step that lands within rounding of
#: the stopping threshold may take one more iteration on another machine
ITERATIVE = Tolerance(
    "iterative",
    1e-6,
    1e-9,
    "converged solves; counts of iterations may move by one where a step lands at the threshold",
)
DESCRIPTIVE = Tolerance(
    "descriptive", 1e-9, 1e-12, "geometry echo or drawing: closed-form coordinates"
)
#: speed tables: nothing in them is compared (timings and their ratios depend on the machine)
TIMING = Tolerance(
    "timing", 0.0, 0.0, "a speed table: timings and their ratios depend on the machine"
)


@dataclass(frozen=True)
class Artefact:
    """One table or figure (or intermediate product) and everything the pipeline needs to know."""

    study: str
    name: str
    make: Callable
    outputs: tuple[str, ...]
    generated: tuple[str, ...] = ()
    needs: tuple[str, ...] = ()
    config: tuple[str, ...] = ()
    tolerance: Tolerance = ROUNDING
    folder: str | None = None
    reference: bool = True
    #: cores the job may use (Snakemake ``threads:``; BLAS/torch thread count of the job)
    threads: int = 1
    #: Snakemake ``resources:`` of the job as ``(name, value)`` pairs, e.g. ``(("runtime", 60),)``
    #: (minutes) and ``mem_mb``: what a cluster scheduler (profiles/slurm) reserves for it
    resources: tuple[tuple[str, int | str], ...] = ()
    #: one-line caption of the artefact in the Snakemake report (default: its docstring's first sentence)
    caption: str = ""
    #: figures drawn from one saved table: (png, csv, draw(frame, path)); a test redraws each
    #: from the committed CSV and compares it with the committed PNG (see :func:`figure`)
    draws: tuple[tuple[str, str, Callable], ...] = ()
    #: files of the repository it reads besides its code, config and reference CSV (paths from the
    #: repository's root, e.g. ``examples/delta.yaml``): inputs of its rule, so an edit reruns it
    files: tuple[str, ...] = ()

    @property
    def key(self) -> str:
        return f"{self.study}:{self.name}"

    @property
    def rule(self) -> str:
        return f"{self.study}_{self.name}"

    @property
    def module(self) -> str:
        return self.make.__module__

    @property
    def study_folder(self) -> str:
        """Folder of the study's outputs under the figures folder ('' = the folder itself)."""
        return self.study if self.folder is None else self.folder

    def output_paths(self, figures: str | Path, generated: str | Path) -> list[str]:
        base = Path(figures) / self.study_folder
        return [str(base / f) for f in self.outputs] + [
            str(Path(generated) / self.study / f) for f in self.generated
        ]

    @property
    def location(self) -> str:
        """``file:line`` of the function that makes the artefact."""
        fn = inspect.unwrap(self.make)
        return f"{inspect.getsourcefile(fn)}:{inspect.getsourcelines(fn)[1]}"

    @property
    def description(self) -> str:
        """The caption of the report: :attr:`caption`, else the first sentence of the docstring."""
        if self.caption:
            return self.caption
        doc = " ".join((inspect.getdoc(inspect.unwrap(self.make)) or self.key).split())
        end = _SENTENCE_END.search(doc)
        return doc if end is None else doc[: end.start() + 1]

    def sources(self) -> list[str]:
        """The parakin source files this artefact runs: its module and everything it imports."""
        return sorted(str(p) for p in _closure(self.module))


#: the end of a docstring's first sentence: a full stop and a space, not after "Fig.", "eq.", "e.g." ...
_SENTENCE_END = re.compile(
    r"(?<!\bFig)(?<!\bFigs)(?<!\beq)(?<!\beqs)(?<!\bEq)(?<!\bvs)(?<!\be\.g)(?<!\bi\.e)"
    r"(?<!\bal)(?<!\bcf)(?<!\bSec)(?<!\bNo)\.\s"
)

#: "study:name" -> Artefact, in declaration order (filled by the study modules' decorators)
REGISTRY: dict[str, Artefact] = {}


def artefact(
    study: str,
    name: str,
    *,
    outputs: Sequence[str],
    generated: Sequence[str] = (),
    needs: Sequence[str] = (),
    config: Sequence[str] = (),
    tolerance: Tolerance = ROUNDING,
    folder: str | None = None,
    reference: bool = True,
    threads: int = 1,
    resources: dict[str, int | str] | None = None,
    caption: str = "",
    draws: Sequence[tuple[str, str, Callable]] = (),
    files: Sequence[str] = (),
) -> Callable:
    """Declare the decorated ``make(config, outdir) -> list[Path]`` as one artefact.

    ``outputs`` are file names in the study's figures folder, ``generated`` in its generated-data
    folder; ``needs`` are ``"study:name"`` keys of upstream artefacts (their outputs become this
    artefact's inputs); ``config`` the dotted config sections it reads (with ``seed`` always);
    ``reference``: whether it reads ``data/reference/<study>.csv``; ``threads`` and ``resources``
    (e.g. ``{"runtime": 60, "mem_mb": 4000}``, minutes and MB) what its Snakemake job reserves (a
    long job says so: the SLURM profile schedules by them); ``caption``: its one line in the report;
    ``files``: repository files it reads besides code, config and reference (its rule's inputs).
    """

    def register(make: Callable) -> Callable:
        if not (isinstance(threads, int) and threads >= 1):
            raise ValueError(
                f"artefact {study}:{name}: threads = {threads!r} must be an integer >= 1"
            )
        item = Artefact(
            study,
            name,
            make,
            tuple(outputs),
            tuple(generated),
            tuple(needs),
            tuple(config),
            tolerance,
            folder,
            reference,
            threads,
            tuple(sorted((resources or {}).items())),
            caption,
            tuple(draws),
            tuple(files),
        )
        old = REGISTRY.get(item.key)
        if old is not None and (old.module, old.make.__qualname__) != (
            item.module,
            make.__qualname__,
        ):
            raise ValueError(
                f"artefact {item.key} declared twice: {old.location} and {item.location}"
            )
        REGISTRY[item.key] = item
        make.artefact = item
        return make

    return register


def table_and_figure(
    study: str,
    name: str,
    stem: str,
    draw: Callable[[Any, Path], Path],
    **declared: Any,
) -> Callable:
    """Declare the decorated ``table(config) -> DataFrame`` as one figure artefact: the table is
    written to ``<stem>.csv`` and the figure drawn from that file into ``<stem>.png`` by ``draw``
    (:func:`parakin.io.write_and_draw`, which hands ``draw`` the final path, so the figure is
    tagged by its name); ``declared``: :func:`artefact`'s other fields. The artefact's
    ``make(config, outdir)`` keeps the table's name and docstring."""

    def register(table: Callable[[dict], Any]) -> Callable:
        @wraps(table)
        def make(config: dict, outdir: Path) -> list[Path]:
            from parakin.io import write_and_draw

            return write_and_draw(table(config), Path(outdir) / f"{stem}.csv", draw)

        return drawn_figure(study, name, stem, draw, **declared)(make)

    return register


def drawn_figures(
    study: str,
    name: str,
    draws: Sequence[tuple[str, str, Callable[[Any, Path], Path]]],
    *more: str,
    **declared: Any,
) -> Callable:
    """Declare an artefact whose figures are each drawn from one of its tables: ``draws`` lists
    ``(png, csv, draw)`` (the decorated ``make(config, outdir)`` writes both, e.g. with
    :func:`parakin.io.draw_from_csv`); its outputs are each figure and its table in that order, then
    the files ``more``; ``declared``: :func:`artefact`'s other fields."""
    outputs = [file for png, csv, _ in draws for file in (png, csv)]
    return artefact(study, name, outputs=[*outputs, *more], draws=draws, **declared)


def drawn_figure(
    study: str, name: str, stem: str, draw: Callable[[Any, Path], Path], *more: str, **declared: Any
) -> Callable:
    """Declare an artefact whose figure ``<stem>.png`` is drawn by ``draw`` from its table
    ``<stem>.csv``, then the files ``more`` (:func:`drawn_figures` with one figure)."""
    return drawn_figures(study, name, [(f"{stem}.png", f"{stem}.csv", draw)], *more, **declared)


def table_files(*stems: str) -> tuple[str, ...]:
    """The files :func:`parakin.io.write_table` writes for each of ``stems``: ``<stem>.csv`` and
    ``<stem>.md``, in that order."""
    return tuple(f"{stem}{suffix}" for stem in stems for suffix in (".csv", ".md"))


def table(study: str, name: str, stem: str, *more: str, **declared: Any) -> Callable:
    """Declare a table artefact: ``<stem>.csv`` and ``<stem>.md`` (:func:`table_files`) then the
    files ``more``, in that order; ``declared``: :func:`artefact`'s other fields."""
    return artefact(study, name, outputs=[*table_files(stem), *more], **declared)


def declarations(study: str) -> tuple[Callable, Callable, Callable, Callable]:
    """:func:`artefact`, :func:`table`, :func:`table_and_figure` and :func:`drawn_figure` with
    ``study`` filled in: what a study's modules declare their artefacts with."""
    return (
        partial(artefact, study),
        partial(table, study),
        partial(table_and_figure, study),
        partial(drawn_figure, study),
    )


def figure(
    study: str, name: str, stem: str, data: Callable, draw: Callable, **declaration
) -> Callable:
    """Declare a figure computed apart from its drawing: ``data(config) -> DataFrame`` and
    ``draw(frame, path)``. The artefact writes ``stem.csv`` (the numbers) and ``stem.png`` drawn
    from that CSV as written, so the committed figure can always be redrawn from the committed CSV.
    ``declaration``: the other arguments of :func:`artefact`."""

    def make(config: dict, outdir: Path) -> list[Path]:
        import pandas as pd

        from parakin.io import atomic_writer, write_csv

        csv = write_csv(data(config), Path(outdir) / f"{stem}.csv")
        frame = pd.read_csv(csv)
        png = atomic_writer(Path(outdir) / f"{stem}.png", lambda path: draw(frame, path))
        return [png, csv]

    make.__name__ = make.__qualname__ = name
    make.__module__ = data.__module__
    make.__doc__ = data.__doc__
    make.__wrapped__ = data  # `parakin which` points at the data function
    more = declaration.pop("outputs", ())
    return drawn_figure(study, name, stem, draw, *more, **declaration)(make)


def import_study(name: str):
    """Import the study module ``name`` and, where it is a package, every module in it (in the
    order of their names), so that all its ``@artefact`` declarations are registered."""
    module = importlib.import_module(name)
    for sub in pkgutil.walk_packages(getattr(module, "__path__", []), name + "."):
        importlib.import_module(sub.name)
    return module


def load(studies: Iterable[str], *, complete: bool = True) -> dict[str, Artefact]:
    """Import the study modules (dotted names) and return the registry restricted to them, in order;
    ``complete``: every artefact they need must be among them (what the pipeline requires). A
    study that is a package (a paper: one module per section) has all its modules imported, in
    the order of their names: its ``__init__`` imports none of them, so that a job that runs one
    artefact imports only the module that declares it (and what that imports)."""
    modules = [import_study(m) for m in studies]
    names = {m.__name__ for m in modules}
    picked = {
        k: a
        for k, a in REGISTRY.items()
        if any(a.module == n or a.module.startswith(n + ".") for n in names)
    }
    unknown = [a.needs for a in picked.values() for n in a.needs if n not in picked]
    if complete and unknown:
        raise ValueError(
            f"artefacts need undeclared upstream artefact(s) {sorted(set(sum(map(list, unknown), [])))}"
        )
    return picked


def of_module(module) -> dict[str, Callable]:
    """``{name: make}`` of the artefacts declared in ``module`` (a module object or dotted name)."""
    name = module if isinstance(module, str) else module.__name__
    return {a.name: a.make for a in REGISTRY.values() if a.module == name}


def find(artefacts: dict[str, Artefact], study: str, name: str) -> Artefact:
    """The artefact ``study:name``, or a one-line error listing the known ones."""
    key = f"{study}:{name}"
    if key not in artefacts:
        known = sorted(a.name for a in artefacts.values() if a.study == study)
        if not known:
            raise ValueError(
                f"unknown study {study!r}; known: {', '.join(sorted({a.study for a in artefacts.values()}))}"
            )
        raise ValueError(f"unknown artefact {name!r} of {study}; known: {', '.join(known)}")
    return artefacts[key]


def which(
    artefacts: dict[str, Artefact],
    path: str | Path,
    figures: str = "figures",
    generated: str = "data/generated",
) -> Artefact | None:
    """The artefact that writes ``path`` (a path under the figures or generated folder), or None."""
    target = Path(path).as_posix().lstrip("./")
    for a in artefacts.values():
        for out in a.output_paths(figures, generated):
            if Path(out).as_posix() == target or target.endswith("/" + Path(out).as_posix()):
                return a
    name = Path(path).name
    parent = Path(path).parent.name
    for a in artefacts.values():  # the record or another results folder: match on study folder/name
        for out in a.outputs:
            if out == name and (
                a.study_folder == parent
                or (a.study_folder == "" and parent not in _STUDY_DIRS(artefacts))
            ):
                return a
    return None


def _STUDY_DIRS(artefacts: dict[str, Artefact]) -> set[str]:
    return {a.study_folder for a in artefacts.values() if a.study_folder}


def prune_config(config: dict, item: Artefact) -> dict:
    """Only what ``item`` reads: the seed, the folders and its declared sections (same nesting)."""
    out = {k: config[k] for k in ("seed", "figures_dir", "generated_dir") if k in config}
    for dotted in item.config:
        src, dst = config, out
        parts = dotted.split(".")
        for part in parts[:-1]:
            if part not in src:
                raise KeyError(f"config has no section {dotted!r} (declared by {item.key})")
            src = src[part]
            dst = dst.setdefault(part, {})
        if parts[-1] not in src:
            raise KeyError(f"config has no section {dotted!r} (declared by {item.key})")
        dst[parts[-1]] = src[parts[-1]]
    return out


@dataclass(frozen=True)
class Job:
    """One pipeline job (one Snakemake rule, one process): the artefacts it makes, in registry
    order. ``small``: one core, the default resources, no artefact upstream or downstream and no
    chunks to gather (a cluster profile sends several such jobs in one submission)."""

    rule: str
    items: tuple[Artefact, ...]
    small: bool

    @property
    def study(self) -> str:
        return self.items[0].study


#: the packages whose study modules name a shared job by their path below them
_STUDY_PACKAGES = ("parakin.papers.", "parakin.studies.")


def _module_rule(module: str) -> str:
    """The rule of the job that makes several artefacts of ``module``: its path below parakin's
    study packages, dots as underscores (``parakin.papers.zhao2017_3p4s.dynamics`` ->
    ``zhao2017_3p4s_dynamics``; a study of one's own: its whole dotted name)."""
    for prefix in _STUDY_PACKAGES:
        if module.startswith(prefix):
            module = module[len(prefix) :]
            break
    return module.replace(".", "_")


def gathers(item: Artefact) -> bool:
    """``item``'s study module scatters its work into chunk files that the artefact gathers (its
    ``chunk_files(config)``: the 6-6 census, workflow/rules/census.smk)."""
    return hasattr(sys.modules.get(item.module), "chunk_files")


def jobs(artefacts: dict[str, Artefact]) -> list[Job]:
    """The pipeline's jobs. The small artefacts of one module (one core, the default resources,
    linked to no other artefact, nothing to gather) share one job, so that the interpreter's
    start, the imports and numba's start are paid once per module instead of once per artefact;
    every other artefact is a job of its own, named by its :attr:`Artefact.rule`. Each artefact
    still reads only its declared config sections (:func:`prune_config`) and writes only its
    outputs; a job reruns when any of its artefacts' code, config or inputs change."""
    linked = {k for a in artefacts.values() for k in (a.key, *a.needs) if a.needs}
    small = {
        k: a.threads == 1 and not a.resources and k not in linked and not gathers(a)
        for k, a in artefacts.items()
    }
    by_module: dict[str, list[Artefact]] = {}
    for key, item in artefacts.items():
        if small[key]:
            by_module.setdefault(item.module, []).append(item)
    out, placed = [], set()
    for key, item in artefacts.items():
        if key in placed:
            continue
        shared = by_module.get(item.module, []) if small[key] else []
        if len(shared) > 1:
            out.append(Job(_module_rule(item.module), tuple(shared), True))
            placed.update(a.key for a in shared)
        else:
            out.append(Job(item.rule, (item,), small[key]))
    rules = [job.rule for job in out]
    clash = sorted({r for r in rules if rules.count(r) > 1})
    if clash:
        raise ValueError(
            f"pipeline rule name(s) {clash} made twice (a module's shared job and an artefact "
            "of the same name): rename the artefact"
        )
    return out


# ---------------------------------------------------------------------------------- source closure
_PACKAGE_ROOT = Path(__file__).resolve().parent


def _module_file(name: str) -> Path | None:
    """The source file of module ``name``, or None (not a module: a name it imports from one).
    parakin's own modules are found by path, nothing imported: ``importlib.util.find_spec``
    imports every parent package of the name, and through them torch, numba, scipy and
    matplotlib, 3.7 CPU-s of each Snakemake start for the digests of the rules' sources."""
    top, _, rest = name.partition(".")
    if top == _PACKAGE_ROOT.name:
        base = _PACKAGE_ROOT.joinpath(*rest.split(".")) if rest else _PACKAGE_ROOT
        for path in (base / "__init__.py", base.parent / f"{base.name}.py"):
            if path.is_file():
                return path.resolve()
        return None
    spec = (
        importlib.util.find_spec(name)
        if name not in sys.modules
        else getattr(sys.modules[name], "__spec__", None)
    )
    origin = getattr(spec, "origin", None)
    return Path(origin).resolve() if origin and origin.endswith(".py") else None


@cache
def _imports(path: Path, package: str) -> tuple[str, ...]:
    """Absolute names of the modules ``path`` imports (relative imports resolved)."""
    tree = ast.parse(path.read_text())
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join([*parts, base] if base else parts)
            found.append(base)
            found += [f"{base}.{a.name}" for a in node.names]
    return tuple(found)


@cache
def _closure(module: str) -> frozenset[Path]:
    """Files of ``module`` and of every module of the same top-level package it imports, transitively."""
    top = module.split(".")[0]
    seen: dict[str, Path] = {}
    todo = [module]
    while todo:
        name = todo.pop()
        if name in seen or not (name == top or name.startswith(top + ".")):
            continue
        try:
            path = _module_file(name)
        except (ImportError, ValueError):
            path = None
        if path is None:
            seen[name] = None
            continue
        seen[name] = path
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        todo += [n for n in _imports(path, package) if n not in seen]
        # importing a.b.c runs a/__init__ and a/b/__init__ first
        parts = name.split(".")
        todo += [".".join(parts[:i]) for i in range(1, len(parts))]
    return frozenset(p for p in seen.values() if p is not None)
