"""The ``dlasweep`` command: grow, sweep, slurm, report, info, bench.

Exit status: 0 success, 2 bad input (one line naming the bad key or value,
nothing written), 1 failure at run time. Every input is checked, output
folders included, before any work starts. This is the only module that
knows ``argv``.

It loads numba, xarray and dask only in the commands that use them, so
that ``--help`` and a bad option answer without loading them (docs/performance.md).
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import os
import sys
import textwrap
import time
import traceback
import warnings
from pathlib import Path

from . import params as _params
from ._entry import command_of, loading
from ._version import __version__
from .bench.targets import MODELS as BENCH_MODELS
from .data import export as _export
from .data.paths import writable
from .params import one_line as _one_line
from .reporting.pictures import DEFAULT_INCHES, MAX_PIXELS, PANEL_PIXELS, check_size
from .sweep import slurm
from .sweep.parts import Interrupted, ResumeError
from .sweep.progress import follow, growth_bar, steps_bar
from .sweep.spec import MAX_PARTICLES, MAX_WORKERS, SpecError, load_spec


class UsageError(ValueError):
    """A bad command line; the message names the option."""


class _Parser(argparse.ArgumentParser):
    """argparse that raises instead of printing usage and exiting."""

    def error(self, message):
        raise UsageError(message)


def main(argv=None) -> int:
    """Run the command line; return the exit status."""
    argv = sys.argv[1:] if argv is None else [str(a) for a in argv]
    command = "dlasweep"
    try:
        parser = _parser()
        args = parser.parse_args(argv)
        if args.command is None:
            _say(parser.format_help().rstrip())
            return 2
        command = f"dlasweep {args.command}"
        with loading():  # numba, xarray and netCDF: the bulk of every command's modules
            from .data import netcdf
        with netcdf.command_line(["dlasweep", *argv]):  # the files' history
            return args.handler(args)
    except SystemExit as done:  # --help, --version
        return int(done.code or 0)
    except BrokenPipeError:  # the reader left (``dlasweep info f.nc | head``): end quietly, as SIGPIPE would
        with contextlib.suppress(OSError):
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141
    except KeyboardInterrupt as err:
        if command == "dlasweep":  # interrupted while parsing
            command = command_of(argv)
        _say(f"{command}: interrupted{err.kept_line() if isinstance(err, Interrupted) else ''}")
        return 130
    except Exception as err:
        if _refusal(err):
            subcommands = next(a.choices for a in parser._actions if isinstance(a, argparse._SubParsersAction))
            if command == "dlasweep" and argv and argv[0] in subcommands:  # refused while parsing its own options
                command = f"dlasweep {argv[0]}"
            _say(f"{command}: {_one_line(err)}")
            return 2
        if not isinstance(err, (OSError, TimeoutError)):
            traceback.print_exc()  # a bug: show where
        _say(f"{command}: failed: {type(err).__name__}: {_one_line(err)}")
        return 1


def _refusal(err) -> bool:
    """Whether ``err`` refuses bad input (exit 2, one line). The store's refusal is looked up only for
    an error that is none of the others: only reading a file raises it, and by then xarray is loaded."""
    if isinstance(err, (UsageError, SpecError, ResumeError)):
        return True
    from .data.schema import StoreError

    return isinstance(err, StoreError)


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="dlasweep", allow_abbrev=False,
                     description="Parameter sweeps of diffusion-limited aggregation.",
                     epilog="examples:\n  dlasweep grow -n 1e5 -o cluster.png\n"
                            "  dlasweep init quick && dlasweep sweep quick.toml && dlasweep report quick.nc\n\n"
                            "`dlasweep COMMAND --help` describes a command.",
                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version", version=f"dlasweep {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND")

    one = _command(commands, "grow", "grow one cluster and save it (.nc), draw it (.png, .svg) or export it "
                   "(.csv, .ply, .obj)",
                   ["dlasweep grow -n 1e5 -o cluster.png",
                    "dlasweep grow -n 2e4 --dim 3 --model offlattice --stickiness 0.3 -o cluster.nc",
                    "dlasweep grow -n 1e4 --no-jumps --seed 7 -o cluster.csv"],
                   "Each option from --model to --max-steps sets a parameter of the model (docs/model.md "
                   "explains them).")
    one.add_argument("-n", type=_params.integer, required=True, help="number of particles, e.g. 100000 or 1e5")
    one.add_argument("--seed", type=_params.integer, default=0, help="random seed (default 0)")
    for name, param in _params.PARAMETERS.items():
        one.add_argument(f"--{name.replace('_', '-')}", dest=name, **_option(name, param))
        if "_" in name:  # the spec's spelling works too, without a second line of help
            one.add_argument(f"--{name}", dest=name, help=argparse.SUPPRESS)
    one.add_argument("-o", "--output", required=True, type=Path, metavar="FILE",
                     help="output file: " + ", ".join(_export.SUFFIXES))
    one.add_argument("--force", action="store_true", help="replace the output file if it exists")
    _output_options(one)
    one.set_defaults(handler=_grow)

    out = _command(commands, "export", "write one stored cluster of a dataset as a table, a mesh or a picture",
                   ["dlasweep export quick.nc --cluster 3 -o cluster.ply --mesh tubes",
                    "dlasweep export quick.nc --cluster 0 -o tree.svg --style tree"])
    out.add_argument("dataset", type=Path, metavar="DATASET",
                     help="netCDF file written by `dlasweep sweep` or `dlasweep grow`")
    out.add_argument("--cluster", type=_params.integer, required=True, metavar="K",
                     help="the cluster's position in the file (0 first; `dlasweep info` counts them)")
    out.add_argument("-o", "--output", required=True, type=Path, metavar="FILE",
                     help="output file: " + ", ".join(_export.SUFFIXES))
    out.add_argument("--force", action="store_true", help="replace the output file if it exists")
    _output_options(out)
    out.set_defaults(handler=_export_cluster)

    many = _command(commands, "sweep", "run a sweep spec (TOML) into a netCDF file",
                    ["dlasweep init quick && dlasweep sweep quick.toml -o quick.nc",
                     "dlasweep sweep quick.toml -o quick.nc --resume   # after an interruption",
                     "dlasweep sweep quick.toml --scheduler-file sched.json"],
                    "The spec's keys are documented in docs/spec.md (the sweep spec); `dlasweep init --list` "
                    "lists example specs to start from.")
    many.add_argument("spec", type=Path, metavar="SPEC", help="sweep spec, e.g. from `dlasweep init quick`")
    many.add_argument("-o", "--output", type=Path, metavar="OUT",
                      help="netCDF file (default: SPEC's name with .nc, here)")
    where = many.add_mutually_exclusive_group()
    where.add_argument("--scheduler", metavar="ADDRESS", help="address of a running dask scheduler")
    where.add_argument("--scheduler-file", type=Path, metavar="FILE", help="dask scheduler file")
    many.add_argument("--workers", type=_params.integer, metavar="K",
                      help="threads of the embedded dask cluster (tasks at once)")
    many.add_argument("--resume", action="store_true",
                      help="continue an interrupted run of this spec (its OUT.parts), replacing OUT if it exists; "
                           "when OUT is already this spec's complete result, nothing to do")
    many.add_argument("--force", action="store_true", help="replace OUT if it exists")
    many.set_defaults(handler=_sweep)

    _slurm_parser(commands)

    start = _command(commands, "init", "write one of the example sweep specs that come with dlasweep",
                     ["dlasweep init --list", "dlasweep init quick -o quick.toml && dlasweep sweep quick.toml"],
                     "Run it as it is, or edit it first: docs/spec.md documents its keys.")
    start.add_argument("name", nargs="?", metavar="NAME", help="the example's name (--list lists them)")
    start.add_argument("-o", "--output", type=Path, metavar="SPEC",
                       help="the spec file to write (default: NAME.toml, here)")
    start.add_argument("--list", action="store_true", help="list the examples, each with what it sweeps")
    start.add_argument("--force", action="store_true", help="replace SPEC if it exists")
    start.set_defaults(handler=_init)

    ahead = _command(commands, "compile", "compile the kernels of each model's first run ahead, into numba's cache",
                     ["dlasweep compile", "dlasweep compile --model lattice-2d --model offlattice-2d"],
                     "A wheel built here (pip install .) carries them already; an editable install, or a wheel "
                     "built on another processor, compiles each model's kernels at its first run, for tens of "
                     "seconds, unless this has run once (a job script may run it before a sweep's workers start).")
    ahead.add_argument("--model", action="append", choices=list(_params.MODEL_KINDS), metavar="MODEL",
                       help=f"only this model (repeat for more): {', '.join(_params.MODEL_KINDS)}; default every one")
    ahead.set_defaults(handler=_compile)

    summary = _command(commands, "report", "write the tables and plots of a sweep's netCDF file",
                       ["dlasweep report quick.nc -o quick"])
    summary.add_argument("dataset", type=Path, metavar="DATASET", help="netCDF file written by `dlasweep sweep`")
    summary.add_argument("-o", "--output", type=Path, metavar="DIR",
                         help="output folder (default: DATASET without .nc); an earlier report there is replaced")
    summary.set_defaults(handler=_report)

    about = _command(commands, "info", "say what a dataset holds: spec, axes, counts, statuses, failed tasks, "
                     "headline D", ["dlasweep info quick.nc", "dlasweep info cluster.nc"])
    about.add_argument("dataset", type=Path, metavar="DATASET",
                       help="netCDF file written by `dlasweep sweep`, `dlasweep grow` or `dlasweep bench`")
    about.set_defaults(handler=_info)

    timing = _command(commands, "bench", "measure the kernels' speed, memory and cost scaling on this machine",
                      ["dlasweep bench --quick -o bench", "dlasweep bench --model lattice-2d -o bench"],
                      "docs/benchmark.md says what each column means.")
    timing.add_argument("-o", "--output", type=Path, default=Path("results/bench"), metavar="DIR",
                        help="output folder (default results/bench)")
    size = timing.add_mutually_exclusive_group()
    size.add_argument("--full", action="store_true",
                      help="add N = 1e7 for every model and print the table of targets: seconds, memory "
                           "per particle, cost exponent")
    size.add_argument("--huge", action="store_true", help="--full, and N = 1e8 for the 2D models (hours)")
    size.add_argument("--quick", action="store_true", help="only the smallest N (a smoke test)")
    timing.add_argument("--model", action="append", choices=list(BENCH_MODELS), metavar="MODEL",
                        help=f"only this model (repeat for more): {', '.join(BENCH_MODELS)}; default every one")
    timing.set_defaults(handler=_bench)
    return parser


def _command(commands, name, summary, examples, description=None):
    """A subcommand's parser: ``summary`` (one line) in the list of commands and atop its help, ``description``
    below it, and its ``examples`` (command lines) at the end of its help."""
    paragraphs = [summary[0].upper() + summary[1:] + ".", *([description] if description else [])]
    text = "\n\n".join(textwrap.fill(paragraph, 79) for paragraph in paragraphs)
    return commands.add_parser(name, allow_abbrev=False, help=summary, description=text,
                               epilog="examples:\n" + "\n".join(f"  {line}" for line in examples),
                               formatter_class=argparse.RawDescriptionHelpFormatter)


def _output_options(command):
    """The options of a cluster's output file: pictures' size and style, meshes' shape."""
    look = command.add_argument_group("pictures (.png, .svg)")
    look.add_argument("--size-inches", type=float, metavar="W",
                      help=f"side of the square picture in inches (default {DEFAULT_INCHES:g})")
    look.add_argument("--dpi", type=float, help=f"dots per inch (default: whole pixels per lattice site, a panel "
                                                f"at least {PANEL_PIXELS} and the picture at most {MAX_PIXELS} "
                                                f"pixels wide)")
    look.add_argument("--style", choices=_export.STYLES,
                      help="disks: the particles, coloured by attachment order (default); tree: one line per "
                           "Horton-Strahler branch, wider by order (.svg: vector paths for a plotter or a cutter)")
    shape = command.add_argument_group("meshes (.ply, .obj)")
    shape.add_argument("--mesh", choices=_export.MESHES,
                       help="spheres: a sphere per particle (default); tubes: a tube along each bond")


def _output(args, out) -> dict:
    """The checked options of the output file ``out`` (``_output_options``): refused where they do not apply."""
    suffix = out.suffix.lower()
    if suffix not in _export.SUFFIXES:
        raise UsageError(f"-o {out}: expected a file ending in {', '.join(_export.SUFFIXES)}")
    for option, given, where in (("--size-inches", args.size_inches, _export.PICTURES),
                                 ("--dpi", args.dpi, _export.PICTURES), ("--style", args.style, _export.PICTURES),
                                 ("--mesh", args.mesh, _export.MESH_FILES)):
        if given is not None and suffix not in where:
            raise UsageError(f"{option}: applies to {', '.join(where)} files, not to {out}")
    picture = {"inches": DEFAULT_INCHES if args.size_inches is None else args.size_inches, "dpi": args.dpi}
    try:
        check_size(**picture)
    except ValueError as err:
        name, _, reason = str(err).partition(":")  # the message starts with the argument's name
        raise UsageError(f"{'--size-inches' if name == 'inches' else '--dpi'}:{reason}") from None
    return {"picture": picture, "style": args.style or _export.STYLES[0], "mesh": args.mesh or _export.MESHES[0]}


def _export_cluster(args) -> int:
    from .data import netcdf, ragged

    out = args.output
    how = _output(args, out)
    _check_dataset(args.dataset)
    _check_writable(out)
    _check_new(out, args.force)
    with netcdf.open_sweep(args.dataset) as ds:
        count = ds.sizes.get("cluster", 0)
        if not 0 <= args.cluster < count:
            raise UsageError(f"--cluster: {args.cluster} is not in [0, {count - 1}]" if count else
                             f"--cluster: {args.dataset} stores no cluster")
        cluster = ragged.read_cluster(ds, args.cluster)
        seed = int(ds["cluster_seed"].values[args.cluster])
    if _export.needs_parents(out, how["style"], how["mesh"]) and cluster.parents is None:
        raise UsageError(f"{args.dataset}: holds no parents (written before dlasweep stored them); "
                         f"{out.suffix} needs them")
    _export.write_cluster(cluster, out, seed, **how)
    print(f"{out}: cluster {args.cluster}, {_params.counted(cluster.n, 'particle')}")
    return 0


def _option(name, param) -> dict:
    """``metavar`` and ``help`` of a model parameter's option, from its row of ``params.PARAMETERS``: a choice
    lists its values, a boolean is a switch and its ``--no-`` form, any other is named by its name's last word
    (``--kill-factor FACTOR``)."""
    default = f"Default: {_params.shown_default(name)}."
    if param.kind is bool:
        return {"action": argparse.BooleanOptionalAction, "help": f"{param.meaning}. {default}"}
    if isinstance(param.values, tuple):
        return {"metavar": "{" + ",".join(map(_params.text, param.values)) + "}", "help": f"{param.meaning}. {default}"}
    return {"metavar": name.rpartition("_")[2].upper(),
            "help": f"{param.meaning}. Allowed: {_params.allowed(name)}. {default}"}


def _grow(args) -> int:
    from .growth.cluster import grow

    out = args.output
    how = _output(args, out)
    _check_writable(out)
    _check_new(out, args.force)
    if not 1 <= args.n <= MAX_PARTICLES:
        raise UsageError(f"-n: {args.n} is not in [1, {MAX_PARTICLES}]")
    if not 0 <= args.seed <= _params.MAX_SEED:
        raise UsageError(f"--seed: {args.seed} is not in [0, {_params.MAX_SEED}]")
    try:
        given = {k: v if isinstance(v, bool) else _params.coerce(k, v)  # a switch's value is bool already
                 for k in _params.DEFAULTS if (v := getattr(args, k)) is not None}
        resolved = _params.resolve(**given)
    except ValueError as err:
        name, _, reason = str(err).partition(":")  # the message starts with the parameter's name
        raise UsageError(f"--{name.replace('_', '-')}:{reason}") from None
    with growth_bar(args.n, resolved) as bar:
        progress = None if bar is None else lambda particles, _: bar.update(particles - bar.n)
        cluster = grow(args.n, args.seed, progress=progress, **resolved)
    if cluster.status != _params.Status.ok.name:
        _say(f"dlasweep grow: stopped early ({cluster.status}) with {cluster.n} of {args.n} particles")
    _export.write_cluster(cluster, out, args.seed, **how)
    print(f"{out}: {_params.counted(cluster.n, 'particle')}")
    return 0


def _sweep_target(args) -> tuple:
    """The spec and the output file of ``sweep`` (and ``slurm``), checked, and whether that file is already
    the complete result of this spec (``--resume`` after the run ended: nothing to do)."""
    spec = load_spec(args.spec)
    out = args.output or Path(args.spec.stem + ".nc")
    if out.suffix != ".nc":
        raise UsageError(f"-o {out}: expected a file ending in .nc")
    _check_writable(out)
    parts = Path(f"{out}.parts").exists()
    why = ""
    if args.resume and not args.force and not parts and out.is_file():
        # A job script that reruns its sweep after a preemption ends green once the sweep is done.
        differs = _differs(spec, out)
        if differs is None:
            return spec, out, True
        why = f" and is not this spec's complete result ({differs}); nothing left to resume"
    elif args.resume:
        why = "; nothing left to resume"
    # Resuming finishes the file an earlier run was writing: it may replace the file it left.
    _check_new(out, args.force or (args.resume and parts), why)
    return spec, out, False


def _differs(spec, out: Path) -> str | None:
    """How the sweep file ``out`` differs from the complete result of ``spec`` (format, spec, failed tasks),
    or None when it is that result."""
    from ._version import FORMAT
    from .data import netcdf
    from .data.schema import StoreError
    from .sweep.spec import differences, parse_spec

    try:
        with netcdf.open_sweep(out) as ds:
            attrs, written = dict(ds.attrs), netcdf.file_format(ds)
    except StoreError as err:
        return _one_line(err).removeprefix(f"{out}: ")
    if written != FORMAT:
        return f"file format {written}, this dlasweep writes {FORMAT}"
    if "spec" not in attrs:
        return "it holds one cluster, not a sweep"
    if attrs.get("failed_tasks"):
        return "tasks failed in it"
    try:
        old = parse_spec(str(attrs["spec"]), default_name=spec.name)
    except SpecError as err:
        return f"its spec: {_one_line(err)}"
    changes = differences(old.identity(), spec.identity())
    changes += [f"{key}: {getattr(old, key)!r} -> {getattr(spec, key)!r}" for key in ("name", "target_ci", "max_seeds")
                if getattr(old, key) != getattr(spec, key)]
    return "; ".join(changes) or None


def _sweep(args) -> int:
    from .sweep import plan as _plan
    from .sweep.runner import run_sweep
    from .sweep.session import embedded_threads, scheduler_address

    spec, out, complete = _sweep_target(args)
    if complete:
        print(f"{out}: complete, nothing to do")
        return 0
    if args.workers is not None:
        if not 1 <= args.workers <= MAX_WORKERS:
            raise UsageError(f"--workers: {args.workers} is not in [1, {MAX_WORKERS}]")
        if args.scheduler or args.scheduler_file:
            raise UsageError("--workers: applies to the embedded cluster only, not with --scheduler")
    if args.scheduler_file and not args.scheduler_file.is_file():
        raise UsageError(f"--scheduler-file {args.scheduler_file}: no such file")
    if args.scheduler is not None or args.scheduler_file:
        try:
            scheduler_address(args.scheduler, args.scheduler_file)
        except ValueError as err:
            option = f"--scheduler-file {args.scheduler_file}" if args.scheduler_file else "--scheduler"
            raise UsageError(f"{option}: {err}") from None
    local = not (args.scheduler or args.scheduler_file)
    plan = _plan.plan(spec, embedded_threads(args.workers or spec.workers) if local else 1)
    _plan.check(plan, spec, _plan.room(out.parent), local=local)

    start = time.perf_counter()
    with warnings.catch_warnings():
        # Failed tasks are reported below, once.
        warnings.simplefilter("ignore", RuntimeWarning)
        ds = run_sweep(spec, client=args.scheduler, out=out, resume=args.resume, workers=args.workers,
                       scheduler_file=args.scheduler_file, announce=f"dlasweep sweep: {plan}")
    failed = ds.attrs.get("failed_tasks")
    ds.close()
    if failed:
        _say(f"dlasweep sweep: {out} written, but tasks failed: {failed}")
        return 1
    grown = ds["n_grown"].size // ds.sizes["n_particles"]
    stored = "" if ds.sizes["cluster"] == grown else f" ({ds.sizes['cluster']} stored)"
    print(f"{out}: {_params.counted(grown, 'cluster')}{stored} in {time.perf_counter() - start:.1f} s")
    return 0


def _slurm_parser(commands):
    """``dlasweep slurm``: the options of ``slurm.Options``, their defaults from it."""
    default = slurm.Options()
    launcher = _command(
        commands, "slurm", "run a sweep spec on SLURM, its dask workers in SLURM jobs",
        ["dlasweep slurm quick.toml -o quick.nc --partition short --cores 8 --memory 16GB --walltime 02:00:00",
         "dlasweep slurm quick.toml --dry-run   # print the job script"],
        description="Needs pip install 'dlasweep[slurm]'; docs/clusters.md tells more. The dask scheduler "
                    "runs in this process (a login node, or a small job of its own); each SLURM job is one "
                    "dask worker with --cores threads. Jobs are added one at a time as tasks wait, a job that "
                    "ends is replaced, workers retire before --walltime runs out, and on any exit (Ctrl-C: "
                    "130, SIGTERM: 143) every job submitted is cancelled, finished tasks kept for --resume.")
    launcher.add_argument("spec", type=Path, metavar="SPEC", help="sweep spec (TOML; docs/spec.md, `dlasweep init`)")
    launcher.add_argument("-o", "--output", type=Path, metavar="OUT",
                          help="netCDF file (default: SPEC's name with .nc, here)")
    launcher.add_argument("--resume", action="store_true",
                          help="continue an interrupted run of this spec (its OUT.parts), replacing OUT if it "
                               "exists; when OUT is already this spec's complete result, nothing to do")
    launcher.add_argument("--force", action="store_true", help="replace OUT if it exists")
    job = launcher.add_argument_group("each worker job")
    job.add_argument("--partition", "--queue", dest="partition", metavar="NAME",
                     help="SLURM partition (default: the default one)")
    job.add_argument("--account", metavar="NAME", help="SLURM account")
    job.add_argument("--cores", type=int, default=default.cores, metavar="N",
                     help=f"CPUs of a job: one dask worker with this many threads (default {default.cores})")
    job.add_argument("--memory", default=default.memory, metavar="SIZE",
                     help=f"memory of a job (default {default.memory})")
    job.add_argument("--walltime", default=default.walltime, metavar="TIME",
                     help=f"wall time of a job, in SLURM's format (default {default.walltime}); workers retire "
                          f"before it ends")
    job.add_argument("--max-jobs", type=int, default=default.max_jobs, metavar="N",
                     help=f"most jobs at once (default {default.max_jobs})")
    job.add_argument("--sbatch", action="append", default=[], metavar="OPTION",
                     help="extra #SBATCH line, e.g. --sbatch '--qos=short' (repeatable)")
    job.add_argument("--python", default=default.python, metavar="PATH",
                     help="Python that runs the workers (default: this one, by absolute path)")
    job.add_argument("--prologue", action="append", default=[], metavar="LINE",
                     help="shell line run before the worker starts, e.g. 'module load ...' (repeatable)")
    job.add_argument("--log-dir", type=Path, default=default.log_dir, metavar="DIR",
                     help=f"folder for the jobs' slurm-<id>.out (default {default.log_dir})")
    job.add_argument("--local-directory", metavar="DIR",
                     help="worker scratch folder (default: dask's, in the job's temporary folder)")
    job.add_argument("--death-timeout", type=float, default=default.death_timeout, metavar="SECONDS",
                     help=f"seconds a worker waits for a lost scheduler before it exits "
                          f"(default {default.death_timeout:g})")
    net = launcher.add_argument_group("network")
    net.add_argument("--interface", metavar="NAME",
                     help="network interface of the scheduler and the workers, e.g. ib0 or lo")
    net.add_argument("--scheduler-host", metavar="ADDRESS",
                     help="address the scheduler listens on (default: --interface's, else the host name's)")
    launcher.add_argument("--log-every", type=int, default=default.log_every, metavar="N",
                          help=f"when stderr is not a terminal, a line per N finished tasks "
                               f"(default {default.log_every})")
    launcher.add_argument("--dry-run", action="store_true",
                          help="check the options and the spec, print the job script and stop")
    launcher.set_defaults(handler=_slurm)


def _slurm(args) -> int:
    """Check everything, then run ``sweep`` on a scheduler whose workers are SLURM jobs."""
    options = slurm.Options(**{field.name: getattr(args, field.name) for field in dataclasses.fields(slurm.Options)})
    _, out, complete = _sweep_target(args)
    if complete:
        print(f"{out}: complete, nothing to do")
        return 0
    try:
        script = slurm.prepare(options, ask_slurm=not args.dry_run)
    except slurm.OptionError as err:
        name, space, reason = str(err).partition(" ")  # the message starts with the option's field name
        raise UsageError(f"--{name.replace('_', '-')}{space}{reason}") from None
    except slurm.SlurmError as err:
        raise UsageError(str(err)) from None
    if args.dry_run:
        print(script)
        return 0

    def sweep(address) -> int:
        argv = ["sweep", args.spec, "-o", out, "--scheduler", address,
                *(["--resume"] if args.resume else []), *(["--force"] if args.force else [])]
        sweep_args = _parser().parse_args([str(a) for a in argv])  # the sweep's own defaults and checks
        return sweep_args.handler(sweep_args)

    def echo(line):
        _say(f"dlasweep slurm {time.strftime('%H:%M:%S')} {line}")

    return slurm.launch(options, sweep, echo, task_lines=not sys.stderr.isatty())


def _init(args) -> int:
    """Write a shipped example spec (``sweep.examples``), or list them."""
    from .sweep import examples

    if args.list:
        if args.name is not None or args.output is not None:
            raise UsageError("--list: takes no NAME or -o")
        width = max(map(len, examples.names()))
        print("\n".join(f"{name:<{width}}  {examples.description(name)}" for name in examples.names()))
        return 0
    if args.name is None:
        raise UsageError(f"NAME: missing; choose one of {', '.join(examples.names())} (--list describes them)")
    try:
        text = examples.text(args.name)
    except KeyError as err:
        raise UsageError(f"NAME: {err.args[0]}") from None
    out = args.output or Path(f"{args.name}.toml")
    _check_writable(out)
    _check_new(out, args.force)
    out.write_text(text, encoding="utf-8")
    print(f"{out}: the {args.name} example; run it with `dlasweep sweep {out}`")
    return 0


def _compile(args) -> int:
    """Compile (or load) each model's first-run kernels (``sweep.precompile``), saying how long each took."""
    from .sweep.precompile import precompile_each

    precompile_each(args.model or _params.MODEL_KINDS,
                    lambda kind, seconds: print(f"{kind}: compiled (or loaded) in {seconds:.1f} s", flush=True))
    return 0


def _report(args) -> int:
    from .data import netcdf
    from .data.schema import is_sweep
    from .reporting.folder import ReportFolderError, earlier_report, report

    _check_dataset(args.dataset)
    outdir = args.output or args.dataset.with_suffix("")
    _check_writable(outdir, folder=True)
    try:
        earlier_report(outdir)
    except ReportFolderError as err:
        raise UsageError(f"-o {err}") from None
    ds = netcdf.open_sweep(args.dataset)
    if not is_sweep(ds):
        ds.close()
        raise UsageError(f"{args.dataset}: holds one cluster (from `dlasweep grow`), not a sweep")
    try:
        with steps_bar("report") as bar:
            report(ds, outdir, progress=None if bar is None else follow(bar))
    finally:
        ds.close()
    print(f"{outdir}: report written")
    return 0


def _info(args) -> int:
    """Print what a dataset holds, in the project's words (``ncdump -h`` gives the raw header)."""
    from .data import netcdf
    from .reporting import info

    _check_dataset(args.dataset)
    ds = netcdf.open_dataset(args.dataset)
    try:
        lines = info.lines(ds)
    finally:
        ds.close()
    history = ds.attrs["history"].replace("\n", "\n  ")  # one line per step
    print("\n".join([f"{args.dataset}: {ds.attrs['title']}", f"  {ds.attrs['source']}, "
                     f"{ds.attrs['Conventions']}; {history}", *lines]))
    return 0


def _bench(args) -> int:
    from .bench.benchmark import analysis_bench, run_bench
    from .bench.chart import plot_bench
    from .data import netcdf

    out = args.output
    _check_writable(out, folder=True)
    lines = []

    def echo(line):
        print(line, flush=True)
        lines.append(line)

    ds = run_bench(full=args.full, quick=args.quick, huge=args.huge, models=args.model, echo=echo)
    if not args.quick:
        ds.attrs.update({f"analysis_{k}": v for k, v in analysis_bench(echo=echo).items()})
    out.mkdir(parents=True, exist_ok=True)
    netcdf.save(ds, out / "bench.nc")
    plot_bench(ds, out)
    (out / "bench.txt").write_text("\n".join(["$ dlasweep bench " + " ".join(sys.argv[2:]), *lines, ""]))
    print(f"{out}: bench.nc, bench.png, bench.txt")
    return 0


def _check_writable(path: Path, folder=False):
    """Refuse, before any work, a target we could not write (``folder``: a folder to fill)."""
    try:
        writable(path, folder)
    except OSError as err:
        raise UsageError(f"-o {err}") from None


def _check_new(path: Path, replace: bool, why=""):
    """Refuse an existing output file unless ``replace``: nothing is overwritten unasked (a link to nowhere
    neither: writing replaces the link)."""
    if (path.exists() or path.is_symlink()) and not replace:
        raise UsageError(f"-o {path}: exists{why}; pass --force to replace it")


def _check_dataset(path: Path):
    """Refuse a folder given as a dataset (a report's folder, say) in one line; ``open_sweep`` checks the rest."""
    if path.is_dir():
        raise UsageError(f"{path}: is a folder, not a netCDF file written by `dlasweep sweep` or `dlasweep grow`")


def _say(line: str):
    print(line, file=sys.stderr)
