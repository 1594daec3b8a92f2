"""``shrm fit``: fit a Lafortune, Cook–Torrance or [RH02] microfacet model to a BRDF (nlopt), or
Koenderink's reciprocal isotropic Zernike expansion (``--model zernike[:order=N][,ridge=R]``:
linear least squares, order and ridge chosen by k-fold cross-validation over the samples, the
held-out errors reported as the fit's errors).

Prints the parameters, the errors and the errors per view-elevation band (rich tables on
stdout, or one JSON object with ``--json``); ``-o params.json`` writes the fit document of
``data_specs/fit_json.md`` atomically, which ``shrmkit.load_brdf`` reads back as the model.
Progress of the multi-start fit goes to stderr. Exit status: 0 when the fit succeeded (every
view band's relative RMS at most 0.5; held out for Zernike), 1 when it failed (the result is
still printed and written), 2 on bad input.

Reference: [RH02] (``data_specs/bibliography.md``).
"""

from __future__ import annotations

import argparse

from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from ..analysis.fit import FitResult, fit_brdf
from ..analysis.fit.fit_file import fit_document, write_fit_json
from ..analysis.fit.zernike import fit_zernike_cv
from ..brdf_io.errors import BadInputError
from ..brdf_io.specs import load_brdf
from .common import print_json, print_table, progress_shown, rgl_brdf_arg, stderr, stdout


def run(args: argparse.Namespace) -> int:
    if args.output and not args.output.lower().endswith(".json"):
        raise BadInputError(args.output, "the output file must end in .json (load_brdf reads it back)")
    source = rgl_brdf_arg(args.brdf, args)
    brdf = load_brdf(source)
    model, model_options = args.model
    if model == "zernike":
        result = fit_zernike_cv(brdf, **model_options, folds=args.folds, seed=args.seed, n_samples=args.samples,
                                max_theta_deg=args.max_theta)
        return _finish(args, result, source, brdf.name)
    with Progress(
        TextColumn("[progress.description]{task.description}"), BarColumn(),
        TextColumn("{task.completed}/{task.total}"), TimeElapsedColumn(),
        console=stderr, transient=True, disable=not progress_shown(args) or not stderr.is_terminal,
    ) as progress:
        task = progress.add_task(f"fitting {model} to {brdf.name}", total=None)

        def report(done: int, total: int) -> None:
            progress.update(task, completed=done, total=total)

        result = fit_brdf(
            brdf, model, lobes=args.lobes, distribution=args.distribution, metric=args.metric,
            seed=args.seed, n_samples=args.samples, starts=args.starts, max_theta_deg=args.max_theta,
            energy_conserving=not args.no_energy, progress=report,
        )
    return _finish(args, result, source, brdf.name)


def _finish(args: argparse.Namespace, result: FitResult, source: str, name: str) -> int:
    """Write, print and judge a fit (exit status 1 when it failed)."""
    if args.output:
        write_fit_json(args.output, result, source=source)
    if args.json:
        print_json(fit_document(result, source=source))
    else:
        _print_tables(result, name)
        if args.output:
            stdout.print(f"wrote {args.output}")
    if not result.success:
        stderr.print(f"shrm fit: warning: {result.message}")
        return 1
    return 0


def _fmt(value: object) -> str:
    if isinstance(value, list):
        return " / ".join(f"{v:.4g}" for v in value)
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)


def _print_tables(result: FitResult, name: str) -> None:
    params = Table(title=f"{result.model} fit of {name}")
    params.add_column("parameter")
    params.add_column("value (r / g / b)", justify="right")
    zernike = result.model == "zernike"
    shown = ({k: result.params[k] for k in ("n_max", "n_coeffs", "ridge", "rank", "negative_fraction")}
             | {"training rel_rms": result.params["training"]["errors"]["rel_rms"],
                "cross-validation folds": result.params["cv"]["folds"]}) if zernike else result.params
    for key, value in shown.items():
        if key == "lobes":
            for k, lobe in enumerate(value, start=1):
                for lk, lv in lobe.items():
                    params.add_row(f"lobe {k} {lk}", _fmt(lv))
        else:
            params.add_row(key, _fmt(value))
    stdout.print(params)

    summary = Table(title=f"errors held out ({result.params['cv']['folds']}-fold cross-validation)" if zernike
                    else "errors")
    for col in ("verdict", "worst band rel_rms", "worst band", "rel_rms (all)", "log_rms", "stop",
                "evaluations", "seconds", "samples", "dropped"):
        summary.add_column(col, justify="right")
    worst = result.worst
    summary.add_row(
        "ok" if result.success else "FAILED", "–" if worst is None else f"{worst.rel_rms:.4g}",
        "–" if worst is None else f"{worst.lo_deg:g}–{worst.hi_deg:g}°",
        f"{result.errors['rel_rms']:.4g}", f"{result.errors['log_rms']:.4g}", result.status,
        str(result.evaluations), f"{result.seconds:.2f}", str(result.n_samples), str(result.n_dropped),
    )
    print_table(summary)

    bands = Table(title="errors per view elevation θ_o" + (", held out" if zernike else ""))
    for col in ("θ_o (deg)", "samples", "rel_rms", "log_rms"):
        bands.add_column(col, justify="right")
    for b in result.bands:
        bands.add_row(f"{b.lo_deg:g}–{b.hi_deg:g}", str(b.n), f"{b.rel_rms:.4g}", f"{b.log_rms:.4g}")
    stdout.print(bands)
    for note in result.at_bounds:
        stdout.print(f"at a bound of the search: {note}", soft_wrap=True)
    spec = result.brdf.to_spec()
    if zernike:  # hundreds of numbers: the fit document (-o, --json) holds the whole spec
        spec = f"{spec[:60]}... ({result.params['n_coeffs']} RGB coefficients; whole in the fit document's model_spec)"
    stdout.print(f"spec: {spec}", soft_wrap=True)
