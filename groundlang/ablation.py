"""The ablation grid: language model x task library x training size, each cell an evaluation.

- language model: ``bow``, ``ibm2``, ``parse`` (:mod:`groundlang.model.language_models`);
- task library: ``authored`` (the shipped ``tasks.lp``) or ``discovered``
  (:func:`groundlang.inference.discovery.discover_tasks` on the cell's
  training instances: demonstrations only, no words, no labels);
- training size: a seeded subset of the corpus, stratified by demonstration
  (instances sharing an initial state and actions form a stratum), and nested:
  every smaller subset is a prefix of the larger ones, so a learning curve
  adds data rather than drawing a new sample per point.

A size equal to the corpus runs the protocol as given (``loo``: one fold per
instance; ``train``: train on all, score all). A smaller size trains one model
on the subset and, under ``loo``, scores the held-out remainder (protocol
``heldout``), under ``train`` the subset itself. Under ``loo`` on the full
corpus, discovery sees every demonstration once (the held-out command's
demonstration is shared by the other commands of its task in the
commands-to-tasks corpus, so leaving it out does not change what can be
discovered); with smaller sizes it sees the training subset only.

Cells run one after another with their folds in ``workers`` processes, or, with
``ray_address``, as Ray tasks (one cell per task) through
:func:`groundlang.distributed.run_on_ray`.
"""

from __future__ import annotations

import logging
import time
from dataclasses import asdict, dataclass, field
from collections.abc import Sequence

import numpy as np

from groundlang.corpus import Corpus
from groundlang.evaluation import evaluate
from groundlang.logic.tasks import TaskLibrary
from groundlang.model.language_models import LANGUAGE_MODELS, get_language_model, setting_names

__all__ = ["LIBRARIES", "AblationRow", "AblationResult", "stratified_order", "training_subset", "run_ablation",
           "format_table", "plot_ablation"]

log = logging.getLogger(__name__)

LIBRARIES = ("authored", "discovered")


@dataclass
class AblationRow:
    """One cell of the grid and its evaluation (``error`` set when the cell failed)."""

    language_model: str
    library: str
    size: int
    protocol: str  # loo, train, or heldout (loo with a size below the corpus)
    accuracy: float | None = None
    correct: int = 0
    n: int = 0
    ci_low: float | None = None
    ci_high: float | None = None
    seconds: float = 0.0
    tasks: list = field(default_factory=list)  # lifted task names of the library used
    failed_folds: int = 0
    error: str | None = None


@dataclass
class AblationResult:
    corpus: str
    corpus_size: int
    protocol: str
    seed: int
    rows: list[AblationRow]
    seconds: float
    language_model_settings: dict = field(default_factory=dict)  # per language model, the settings given

    def to_json(self) -> dict:
        return {"corpus": self.corpus, "corpus_size": self.corpus_size, "protocol": self.protocol,
                "seed": self.seed, "seconds": self.seconds, "rows": [asdict(r) for r in self.rows],
                "language_model_settings": self.language_model_settings}

    @classmethod
    def from_json(cls, data: dict) -> "AblationResult":
        """The result ``to_json`` wrote (``groundlang ablate --json``); ValueError, naming what is missing, for
        anything else, such as the rows of ``ablate --held-out-likelihood --json`` (a table of its own)."""
        missing = [k for k in ("corpus", "corpus_size", "protocol", "seed", "rows", "seconds")
                   if not isinstance(data, dict) or k not in data]
        if missing:
            other = (" (it is the table of `ablate --held-out-likelihood --json`, which says how held-out "
                     "likelihood moves with each switch)" if isinstance(data, dict) and "folds" in data else "")
            raise ValueError(f"not the JSON of an `ablate` grid: it has no {', '.join(missing)}{other}")
        return cls(data["corpus"], data["corpus_size"], data["protocol"], data["seed"],
                   [AblationRow(**r) for r in data["rows"]], data["seconds"],
                   dict(data.get("language_model_settings", {})))

    def table(self) -> str:
        return format_table(self.rows)


# ---------------------------------------------------------------- training subsets


def stratified_order(corpus: Corpus, seed: int = 0) -> list[int]:
    """All instance indices in an order whose every prefix is stratified by demonstration.

    Each stratum is shuffled (seeded); an instance at rank ``r`` of a stratum
    of ``n`` sorts by its quantile ``(r + 0.5) / n``, ties broken by a seeded
    stratum order, so any prefix of length ``k`` holds ``k n / N`` (+-1) of
    each stratum.
    """
    rng = np.random.default_rng(seed)
    strata: dict = {}
    for k, inst in enumerate(corpus.instances):
        strata.setdefault((inst.initial_state, inst.actions), []).append(k)
    groups = list(strata.values())
    tie = rng.permutation(len(groups))
    keyed = []
    for g, members in enumerate(groups):
        shuffled = [members[j] for j in rng.permutation(len(members))]
        keyed.extend(((r + 0.5) / len(members), int(tie[g]), k) for r, k in enumerate(shuffled))
    return [k for _, _, k in sorted(keyed)]


def training_subset(corpus: Corpus, size: int, seed: int = 0) -> list[int]:
    """Sorted indices of a seeded, demonstration-stratified subset of ``size`` instances.

    Raises ValueError unless ``2 <= size <= len(corpus)``.
    """
    if not 2 <= size <= len(corpus):
        raise ValueError(f"{corpus.directory}: training size {size} must be between 2 and the corpus size "
                         f"{len(corpus)}")
    return sorted(stratified_order(corpus, seed)[:size])


# ---------------------------------------------------------------- cells

_CELLS: dict = {}


def _init_cell_worker(context: dict) -> None:
    import torch

    torch.set_num_threads(1)
    _CELLS.clear()
    _CELLS.update(context)


def _cell_protocol(protocol: str, full: bool) -> str:
    return protocol if full or protocol == "train" else "heldout"


def _run_cell(index: int) -> dict:
    """Evaluate one cell of the grid (in this process or a Ray worker); returns an AblationRow as a dict."""
    ctx = _CELLS
    lm, library_name, size = ctx["cells"][index]
    corpus: Corpus = ctx["corpus"]
    full = size >= len(corpus)
    row = AblationRow(lm, library_name, size, _cell_protocol(ctx["protocol"], full))
    started = time.perf_counter()
    try:
        library = ctx["libraries"][(library_name, size)]
        options = dict(ctx["learner_options"])
        if library is not None:
            options["library"] = library
        result = evaluate(
            corpus, ctx["labels"], protocol=ctx["protocol"], language_model=lm,
            workers=ctx["workers"], progress=ctx["progress"], limit=ctx["limit"], learner_options=options,
            train_indices=None if full else ctx["subsets"][size], language_model_settings=ctx["settings"][lm],
        )
    except (ValueError, RuntimeError) as exc:
        row.error = f"{type(exc).__name__}: {exc}"
        row.seconds = time.perf_counter() - started
        return asdict(row)
    row.accuracy, row.correct, row.n = result.accuracy, result.correct, result.n
    row.ci_low, row.ci_high = result.ci_low, result.ci_high
    row.failed_folds = len(result.failed_folds)
    row.seconds = ctx["library_seconds"].get((library_name, size), 0.0) + result.seconds
    row.tasks = ctx["task_names"][(library_name, size)]
    return asdict(row)


def _settings_by_model(language_models: Sequence[str], settings: dict) -> dict[str, dict]:
    """Per language model, the settings it takes; each is checked once by building the model."""
    by_model = {lm: {k: v for k, v in settings.items() if k in setting_names(lm)} for lm in language_models}
    unused = [k for k in settings if not any(k in taken for taken in by_model.values())]
    if unused:
        raise ValueError(f"no language model of the grid ({', '.join(language_models)}) has the setting "
                         f"{unused[0]!r}")
    for lm, taken in by_model.items():
        get_language_model(lm, **taken)  # raises ValueError for a bad value
    return by_model


def _library_for(name: str, instances: Sequence, cache_dir, progress: bool):
    if name == "authored":
        return None
    from groundlang.inference.discovery import discover_tasks

    return discover_tasks(instances, cache_dir=cache_dir, progress=progress).library


def run_ablation(
    corpus: Corpus,
    labels,
    language_models: Sequence[str] = ("bow", "ibm2", "parse"),
    libraries: Sequence[str] = LIBRARIES,
    sizes: Sequence[int] | None = None,
    protocol: str = "loo",
    seed: int = 0,
    workers: int = 1,
    ray_address: str | None = None,
    progress: bool = False,
    limit: int | None = None,
    learner_options: dict | None = None,
    language_model_settings: dict | None = None,
) -> AblationResult:
    """Evaluate every (language model, library, size) cell; ``sizes`` default to the whole corpus.

    ``language_model_settings`` apply to each language model of the grid that takes them
    (``{"mention_phrases": "any"}`` changes ``parse`` only). Raises ValueError for unknown names,
    a setting no model of the grid takes or a bad value, bad sizes or protocol. A cell that
    fails is kept as a row with ``error`` set.
    """
    from groundlang.inference.likelihoods import cache_directory

    started = time.perf_counter()
    unknown = [m for m in language_models if m not in LANGUAGE_MODELS]
    if unknown or not language_models:
        raise ValueError(f"unknown language model(s) {unknown}; expected some of {', '.join(LANGUAGE_MODELS)}")
    unknown = [x for x in libraries if x not in LIBRARIES]
    if unknown or not libraries:
        raise ValueError(f"unknown task librar(y/ies) {unknown}; expected some of {', '.join(LIBRARIES)}")
    if protocol not in ("loo", "train"):
        raise ValueError(f"unknown protocol {protocol!r}; expected loo or train")
    settings = _settings_by_model(language_models, language_model_settings or {})
    sizes = sorted(set(sizes)) if sizes else [len(corpus)]
    subsets = {s: training_subset(corpus, s, seed) for s in sizes}  # raises on a bad size
    options = dict(learner_options or {})
    # Absolute, so that Ray workers (other working directories) share the driver's cache.
    options.setdefault("cache_dir", cache_directory(options.get("cache_dir")).resolve())

    # Libraries are built once per (library, size) in the driver and shared by the language models.
    built, task_names, library_seconds = {}, {}, {}
    for name in libraries:
        for s in sizes:
            t = time.perf_counter()
            try:
                lib = _library_for(name, [corpus.instances[k] for k in subsets[s]], options["cache_dir"], progress)
            except ValueError as exc:
                log.warning("ablation: no %s library at size %d: %s", name, s, exc)
                lib = exc
            library_seconds[(name, s)] = time.perf_counter() - t
            built[(name, s)] = lib
            if isinstance(lib, ValueError):
                task_names[(name, s)] = []
            else:
                task_names[(name, s)] = (lib if lib is not None else TaskLibrary.load()).names

    cells = [(lm, name, s) for name in libraries for lm in language_models for s in sizes]
    runnable = [i for i, (_, name, s) in enumerate(cells) if not isinstance(built[(name, s)], ValueError)]
    context = {
        "corpus": corpus, "labels": labels, "cells": cells, "protocol": protocol, "subsets": subsets,
        "libraries": {k: v for k, v in built.items() if not isinstance(v, ValueError)},
        "task_names": task_names, "library_seconds": library_seconds, "learner_options": options,
        "settings": settings,
        "limit": limit, "progress": progress and ray_address is None,
        "workers": workers if ray_address is None else 1,
    }
    if ray_address is not None:
        from groundlang.distributed import run_on_ray

        records = run_on_ray(_init_cell_worker, _run_cell, context, runnable, ray_address)
    else:
        _init_cell_worker(context)
        records = []
        for i in runnable:
            log.info("ablation: cell %s", cells[i])
            records.append(_run_cell(i))
    by_index = dict(zip(runnable, records))
    rows = []
    for i, (lm, name, s) in enumerate(cells):
        record = by_index.get(i)
        if record is None:
            rows.append(AblationRow(lm, name, s, _cell_protocol(protocol, s >= len(corpus)),
                                    error=f"ValueError: {built[(name, s)]}"))
        elif "language_model" not in record:  # a Ray task that failed outside evaluate
            rows.append(AblationRow(lm, name, s, _cell_protocol(protocol, s >= len(corpus)),
                                    error=record.get("error", "unknown error")))
        else:
            rows.append(AblationRow(**record))
    return AblationResult(str(corpus.directory), len(corpus), protocol, seed, rows, time.perf_counter() - started,
                          {lm: taken for lm, taken in settings.items() if taken})


# ---------------------------------------------------------------- presenting


def format_table(rows: Sequence[AblationRow]) -> str:
    """The rows as a plain-text table (accuracy with 95% Wilson interval, n, seconds)."""
    lines = [f"{'language model':<15}{'library':<12}{'size':>6}  {'protocol':<9}{'accuracy':>9}  "
             f"{'95% CI':<17}{'n':>5}{'seconds':>9}  tasks"]
    for r in rows:
        if r.error is not None:
            lines.append(f"{r.language_model:<15}{r.library:<12}{r.size:>6}  {r.protocol:<9}{'failed':>9}  {r.error}")
            continue
        ci = f"[{r.ci_low:.1%}, {r.ci_high:.1%}]"
        lines.append(f"{r.language_model:<15}{r.library:<12}{r.size:>6}  {r.protocol:<9}{r.accuracy:>9.1%}  "
                     f"{ci:<17}{r.n:>5}{r.seconds:>9.1f}  {', '.join(r.tasks)}")
    return "\n".join(lines)


def plot_ablation(rows: Sequence[AblationRow], ax=None, title: str | None = None):
    """Accuracy (with 95% intervals) against training size, one line per (language model, library).

    With a single size, grouped bars instead. Returns the matplotlib Axes.
    """
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(6.4, 4.0))
    ok = [r for r in rows if r.error is None]
    series: dict = {}
    for r in ok:
        series.setdefault((r.language_model, r.library), []).append(r)
    sizes = sorted({r.size for r in ok})
    if len(sizes) <= 1:
        labels = [f"{lm}\n{lib}" for lm, lib in series]
        acc = [s[0].accuracy for s in series.values()]
        err = np.array([[s[0].accuracy - s[0].ci_low, s[0].ci_high - s[0].accuracy] for s in series.values()]).T
        colours = ["C0" if lib == "authored" else "C1" for _, lib in series]
        ax.bar(range(len(acc)), acc, yerr=err if len(acc) else None, color=colours, capsize=4)
        ax.set_xticks(range(len(acc)), labels)
        ax.set_xlabel(f"language model / task library (training size {sizes[0] if sizes else '?'})")
    else:
        for (lm, lib), items in sorted(series.items()):
            items = sorted(items, key=lambda r: r.size)
            x = [r.size for r in items]
            y = [r.accuracy for r in items]
            err = [[r.accuracy - r.ci_low for r in items], [r.ci_high - r.accuracy for r in items]]
            ax.errorbar(x, y, yerr=err, marker="o", capsize=3, linestyle="-" if lib == "authored" else "--",
                        label=f"{lm}, {lib}")
        ax.set_xlabel("training instances")
        ax.legend(fontsize="small")
    ax.set_ylim(0, 1.05)
    ax.set_ylabel("accuracy (95% Wilson interval)")
    if title:
        ax.set_title(title)
    return ax
