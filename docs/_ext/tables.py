"""Pages of the documentation made from the package's own tables, when the site builds.

A table in the docs that repeats a table of the code drifts from it; these are
written from the code at every build instead, into ``docs/_generated/`` (not
committed), and the pages include them:

- ``parameters.md``: the model parameters, from ``PARAMETERS``;
- ``spec_keys.md``: the keys of a sweep spec, from the spec's key lists and ``PARAMETERS``;
- ``dataset.md``: the variables of a dataset, from ``SCHEMA``;
- ``lesson.ipynb``: the lesson ``workflows/teach.py`` as a notebook, set to a small
  size, which myst-nb runs so that its pictures and numbers are real.

Each module is looked up where the package's layout puts it (``dlasweep.growth.params``,
``dlasweep.sweep.spec``, ``dlasweep.data.schema``), and where it was before
(``dlasweep.params``, ...), so the docs build on either side of that move.
A file is rewritten only when its text changes, so that Sphinx rereads only what changed.
"""

from __future__ import annotations

import importlib
import shutil
from pathlib import Path

from sphinx.errors import ExtensionError

DOCS = Path(__file__).resolve().parent.parent
GENERATED = DOCS / "_generated"
TEACH = DOCS.parent / "workflows" / "teach.py"

LESSON_N = 2000
"""Particles of each cluster when the docs run the lesson: its smallest size (teach.py refuses fewer, which
leave no decade to fit), so the build takes seconds once the kernels are compiled."""
LESSON_SEED = 1
LESSON_OUTPUT = "lesson-output"
"""The lesson's output folder, in docs/_generated/ (where myst-nb runs it), emptied before each build."""

# What each key of a spec's [grid], [run] and [measure] tables means (the [model] keys are the parameters, from their
# table). The build fails when the spec's key lists and these disagree, so a new key cannot go unwritten.
SPEC_KEYS = {
    ("", "name"): ("the file's name without `.toml`", "The sweep's name, in the dataset's title and the report."),
    ("grid", "size"): ("`[0]`", "Box sides, in lattice spacings (particle diameters off the lattice); 0 is "
                                "unbounded. A list: one more axis of the sweep."),
    ("grid", "n_particles"): ("required", "Particle counts at which each cluster is measured. Each cluster is "
                                          "grown once, to the largest; the smaller counts are its prefixes."),
    ("grid", "seeds"): ("1", "A count (replicates 0, 1, ..., n-1) or a list of replicate numbers. With "
                                    "`target_ci`, a count: the first batch."),
    ("run", "root_seed"): ("0", "Every cluster's random stream derives from it and the cluster's grid "
                                       "indices, so results do not depend on the workers or the order tasks end."),
    ("run", "workers"): ("the cores", "Threads of the embedded dask cluster."),
    ("run", "target_ci"): ("none", "Add seeds, batch after batch, until the 95% interval of the headline D at the "
                                   "largest count is at most this half-width in every configuration."),
    ("run", "max_seeds"): ("256", "With `target_ci`: the most seeds grown per configuration."),
    ("run", "store_clusters"): ("`\"all\"`", "Whose particle positions the file keeps: `\"all\"`, `\"none\"`, or "
                                             "an integer K, the first K seeds of each configuration. Every curve "
                                             "is measured for every cluster either way."),
    ("measure", "harmonic_walkers"): ("0 (off)", "Walkers fired at each cluster at its largest count, moved as in "
                                                 "growth but not attached: its harmonic measure, the spectrum D(q) "
                                                 "and the deposition depth (the `harmonic_` variables; see "
                                                 "{doc}`harmonic`)."),
}


def _module(new: str, old: str):
    """The module at its path in the new layout, else at its old path."""
    try:
        return importlib.import_module(new)
    except ModuleNotFoundError as first:
        try:
            return importlib.import_module(old)
        except ModuleNotFoundError:
            raise first from None


def _cell(text) -> str:
    """Text for a Markdown table cell: pipes escaped, and asterisks (``2**dim``) kept literal."""
    return str(text).replace("|", "\\|").replace("*", "\\*")


def parameters_md() -> str:
    params = _module("dlasweep.growth.params", "dlasweep.params")
    lines = ["| name | default | allowed values | kind | meaning |", "|---|---|---|---|---|"]
    for name, par in params.PARAMETERS.items():
        meaning = f"{par.meaning}; {par.note}" if par.note else par.meaning
        kind = "method" if par.shortcut else "model"
        lines.append(f"| `{name}` | `{params.shown_default(name)}` | {_cell(params.allowed(name))} | {kind} | "
                     f"{_cell(meaning)} |")
    return "\n".join(lines) + "\n"


def spec_keys_md() -> str:
    spec = _module("dlasweep.sweep.spec", "dlasweep.spec")
    params = _module("dlasweep.growth.params", "dlasweep.params")
    keys = [("", k) for k in spec._TOP_KEYS] + [("grid", k) for k in spec._GRID_KEYS] + \
        [("run", k) for k in spec._RUN_KEYS] + [("measure", k) for k in getattr(spec, "_MEASURE_KEYS", ())]
    missing = [k for k in keys if k not in SPEC_KEYS]
    stale = [k for k in SPEC_KEYS if k not in keys]
    if missing or stale:
        raise ExtensionError(f"docs/_ext/tables.py SPEC_KEYS: keys of the spec not described {missing}, "
                             f"described keys the spec does not have {stale}")
    lines = ["| table | key | default | meaning |", "|---|---|---|---|"]
    for section, key in keys:
        default, meaning = SPEC_KEYS[section, key]
        lines.append(f"| {f'`[{section}]`' if section else '(top)'} | `{key}` | {default} | {meaning} |")
    for name, par in params.PARAMETERS.items():
        lines.append(f"| `[model]` | `{name}` | `{params.shown_default(name)}` | {_cell(par.meaning)} "
                     f"(allowed: {_cell(params.allowed(name))}) |")
    return "\n".join(lines) + "\n"


def dataset_md() -> str:
    import numpy as np

    schema = _module("dlasweep.data.schema", "dlasweep.schema")
    params = _module("dlasweep.growth.params", "dlasweep.params")
    lines = ["| variable | dimensions | type | units | meaning |", "|---|---|---|---|---|"]
    for name, var in schema.SCHEMA.items():
        if name in params.PARAMETERS:
            continue
        dims = ", ".join("(swept parameters)" if d == "..." else f"`{d}`" for d in var.dims)
        kind = np.dtype(var.dtype).name if var.dtype is not None else "int32 (lattice) or float64"
        kind = "string" if var.dtype is str else kind
        lines.append(f"| `{name}` | {dims} | {kind} | {var.units or ''} | {_cell(var.long_name)} |")
    return "\n".join(lines) + "\n"


def lesson_ipynb() -> str:
    """workflows/teach.py as a notebook, with a cell after its parameters that sets the small size."""
    import jupytext
    import nbformat

    nb = jupytext.read(TEACH)
    at = next(k for k, cell in enumerate(nb.cells) if "parameters" in cell.metadata.get("tags", []))
    note = nbformat.v4.new_markdown_cell(
        f"On this page the lesson runs at n = {LESSON_N:,} particles, seed {LESSON_SEED}, so that the "
        "documentation builds in seconds: the pictures and numbers below come from that run. The "
        "lesson's own size, 50,000, gives the fits a wider range of n.")
    small = nbformat.v4.new_code_cell(f"n, seed, output = {LESSON_N}, {LESSON_SEED}, {LESSON_OUTPUT!r}")
    # The cell of helpers (the command line, the plot) after the parameters: folded, the lesson reads on.
    helpers = nb.cells[at + 1]
    if helpers.cell_type == "code":
        helpers.metadata.setdefault("tags", []).append("hide-input")
    # The lesson writes its plot of both measurements to a file; the page shows it below the cell that drew it.
    plot = [k for k, cell in enumerate(nb.cells) if cell.cell_type == "code" and "dimension.png" in cell.source
            and "def " not in cell.source]
    if len(plot) != 1:
        raise ExtensionError(f"docs/_ext/tables.py: {TEACH.name} has {len(plot)} cells drawing dimension.png, "
                             "not one: say which cell the page should show the plot after")
    show = nbformat.v4.new_code_cell("from IPython.display import Image\n"
                                     "Image(filename=str(Path(output) / 'dimension.png'))")
    show.metadata["tags"] = ["remove-input"]
    nb.cells.insert(plot[0] + 1, show)
    # papermill's convention: the cell after the one tagged "parameters" sets them anew
    nb.cells[at + 1:at + 1] = [note, small]
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    for k, cell in enumerate(nb.cells):
        cell.id = f"cell-{k}"
    return nbformat.writes(nb)


def _write(name: str, text: str):
    path = GENERATED / name
    if not path.exists() or path.read_text() != text:
        path.write_text(text)


def generate(app=None):
    GENERATED.mkdir(exist_ok=True)
    shutil.rmtree(GENERATED / LESSON_OUTPUT, ignore_errors=True)  # the lesson's pictures: this build's alone
    _write("parameters.md", parameters_md())
    _write("spec_keys.md", spec_keys_md())
    _write("dataset.md", dataset_md())
    _write("lesson.ipynb", lesson_ipynb())


def setup(app):
    app.connect("builder-inited", generate)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
