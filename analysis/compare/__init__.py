"""Comparators: Cabral et al. 1999 RSIBR, Kautz & McCool 2000, Green et al. 2007 Gaussian lobes.

``compare(brdf, env, ...)`` (:func:`.table.compare`) builds every representation and returns
one JSON-able table of errors against the angular reference and of costs.
"""

from .table import compare

__all__ = ["compare"]
