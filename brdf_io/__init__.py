"""BRDF and environment-map input/output, analytic models and the reflection-vector
reparameterization (DESIGN §1–3)."""

from .brdf import BRDF
from .errors import BadInputError, ScatteredEvalError, ShrmError
from .specs import brdf_from_spec, load_brdf

__all__ = ["BRDF", "BadInputError", "ScatteredEvalError", "ShrmError", "brdf_from_spec", "load_brdf"]
