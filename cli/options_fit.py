"""``shrm fit``'s parser (numpy-free; the verb's work is in ``cmd_fit.py``)."""

from __future__ import annotations

import argparse

from ..analysis.defaults import DEFAULT_FOLDS, FIT_METRICS, FIT_MODELS
from ..brdf_io.names import ZERNIKE_MAX_ORDER
from .options import add_rgl_incident, brdf_help, number_in

__all__ = ["HELP", "MODEL_CHOICES", "model_arg", "add_arguments"]

HELP = "fit a Lafortune, Cook-Torrance, microfacet (nlopt) or Zernike (cross-validated) model to a BRDF"


def _int_in(lo: int, hi: int):
    return number_in(lo, hi, integer=True)


_angle = number_in(0.0, 90.0, lo_open=True, unit=" degrees")


#: ``--model`` values: the nlopt models and the Zernike expansion (options after ``zernike:``)
MODEL_CHOICES = (*FIT_MODELS, "zernike")


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
        "--metric", choices=FIT_METRICS, default="rel",
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
