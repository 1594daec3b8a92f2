"""``shrm fit``: fit a Lafortune, Cook–Torrance or RH02 microfacet model to a BRDF (nlopt), or
Koenderink's reciprocal isotropic Zernike expansion (``--model zernike[:order=N][,ridge=R]``:
linear least squares, order and ridge chosen by k-fold cross-validation over the samples, the
held-out errors reported as the fit's errors).

Prints the parameters, the errors and the errors per view-elevation band (rich tables on
stdout, or one JSON object with ``--json``); ``-o params.json`` writes the fit document of
``data_specs/fit_json.md`` atomically, which ``shrmkit.load_brdf`` reads back as the model.
Progress of the multi-start fit goes to stderr. Exit status: 0 when the fit succeeded (every
view band's relative RMS at most 0.5; held out for Zernike), 1 when it failed (the result is
still printed and written), 2 on bad input.

Reference: R. Ramamoorthi, P. Hanrahan, "Frequency Space Environment Map Rendering",
SIGGRAPH 2002 (RH02), doi:10.1145/566654.566611.
"""

from __future__ import annotations

import argparse

from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from ..analysis.fit import FitResult, fit_brdf
from ..analysis.fit.crossval import DEFAULT_FOLDS
from ..analysis.fit.fit_file import fit_document, write_fit_json
from ..analysis.fit.metrics import METRICS
from ..analysis.fit.models_param import MODELS
from ..analysis.fit.zernike import MAX_ORDER as ZERNIKE_MAX_ORDER
from ..analysis.fit.zernike import fit_zernike_cv
from ..brdf_io.errors import BadInputError
from ..brdf_io.specs import load_brdf
from .common import add_rgl_incident, brdf_help, number_in, print_json, print_table, rgl_brdf_arg, stderr, stdout

HELP = "fit a Lafortune, Cook-Torrance, microfacet (nlopt) or Zernike (cross-validated) model to a BRDF"


def _int_in(lo: int, hi: int):
    return number_in(lo, hi, integer=True)


_angle = number_in(0.0, 90.0, lo_open=True, unit=" degrees")
#: ``--model`` values: the nlopt models and the Zernike expansion (options after ``zernike:``)
MODEL_CHOICES = (*MODELS, "zernike")


def model_arg(text: str) -> tuple[str, dict[str, float | int]]:
    """``--model``: a name from :data:`MODEL_CHOICES`; ``zernike:order=N,ridge=R`` fixes the Zernike
    order (0..20) and/or ridge (>= 0) instead of choosing them by cross-validation."""
    name, _, rest = text.strip().partition(":")
    if name not in MODEL_CHOICES:
        raise argparse.ArgumentTypeError(f"invalid choice: {text!r} (choose from {', '.join(MODEL_CHOICES)}, "
                                         "zernike:order=N,ridge=R)")
    if rest and name != "zernike":
        raise argparse.ArgumentTypeError(f"{name!r} takes no options after ':' (got {text!r})")
    options: dict[str, float | int] = {}
    for item in filter(None, (part.strip() for part in rest.split(","))):
        key, eq, value = item.partition("=")
        try:
            if key == "order" and eq:
                options["n_max"] = int(value)
                if not 0 <= options["n_max"] <= ZERNIKE_MAX_ORDER:
                    raise ValueError
            elif key == "ridge" and eq:
                options["ridge"] = float(value)
                if not (options["ridge"] >= 0 and options["ridge"] < float("inf")):
                    raise ValueError
            else:
                raise KeyError(key)
        except KeyError:
            raise argparse.ArgumentTypeError(f"unknown Zernike option {item!r}; valid: order=N "
                                             f"(0..{ZERNIKE_MAX_ORDER}), ridge=R (>= 0)") from None
        except ValueError:
            raise argparse.ArgumentTypeError(f"bad Zernike option {item!r}: order is an integer in "
                                             f"0..{ZERNIKE_MAX_ORDER}, ridge a finite number >= 0") from None
    return name, options


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("brdf", help=brdf_help())
    parser.add_argument("--model", type=model_arg, default=("lafortune", {}), metavar="MODEL",
                        help=f"model to fit: {', '.join(MODEL_CHOICES)} (default lafortune); zernike:order=N,ridge=R "
                        "fixes the order and/or ridge that cross-validation would choose")
    parser.add_argument("--folds", type=_int_in(2, 20), default=DEFAULT_FOLDS,
                        help=f"Zernike: cross-validation folds (default {DEFAULT_FOLDS})")
    parser.add_argument("--lobes", type=_int_in(1, 4), default=1, help="Lafortune lobes (default 1)")
    parser.add_argument(
        "--distribution", choices=("beckmann", "ggx"), default="beckmann",
        help="Cook-Torrance distribution (default beckmann)",
    )
    parser.add_argument(
        "--metric", choices=METRICS, default="rel",
        help="error minimized: rel = cosine-weighted relative RMS, log = log-space RMS (default rel)",
    )
    parser.add_argument("--seed", type=_int_in(0, 2**31 - 1), default=0, help="seed (default 0)")
    parser.add_argument("--samples", type=_int_in(256, 1 << 22), default=32768,
                        help="direction pairs drawn for tables and models (default 32768)")
    parser.add_argument("--starts", type=_int_in(1, 64), default=4, help="multi-start seeds (default 4)")
    parser.add_argument("--max-theta", type=_angle, default=80.0,
                        help="ignore samples with theta_i or theta_o above this, degrees (default 80)")
    parser.add_argument("--no-energy", action="store_true",
                        help="do not constrain the fit to conserve energy")
    parser.add_argument("--json", action="store_true", help="print the fit document as one JSON object")
    parser.add_argument("-o", "--output", help="write the fit document (JSON) to this file")
    add_rgl_incident(parser)


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
        console=stderr, transient=True, disable=args.json or not stderr.is_terminal,
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
