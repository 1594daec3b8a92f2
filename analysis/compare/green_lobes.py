"""Builder of the Gaussian-lobe rows [Green07]: K isotropic Gaussian lobes per view elevation
over a spherical-Gaussian mip stack (``gaussian_lobes_model`` of
:mod:`shrmkit.analysis.baselines.methods`).

One row ``gaussian_lobes_k{K}`` per K in ``options.lobes`` (earlier keys ``gaussian_k{K}``); the
transfer samples and the mip stack are made once and shared by every K. The mip stack does not
depend on the view, so a distant viewer has no per-frame CPU work: ``update_s = 0``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ...brdf_io.latlong import pixel_directions
from ..baselines.gaussian_lobes import GaussianLobeModel, sg_mip_stack
from ..baselines.methods import GAUSSIAN_MAX_VIEW_DEG, gaussian_lobes_model, gaussian_transfer_samples
from .representation import BuildContext, BuiltRepresentation

__all__ = ["LobeMaps", "build_green_lobes"]

#: Largest view elevation of the fits, degrees: the table's ``GAUSSIAN_MAX_VIEW_DEG`` (earlier name).
MAX_FIT_VIEW_DEG = GAUSSIAN_MAX_VIEW_DEG


@dataclass(frozen=True, eq=False)
class LobeMaps:
    """A :class:`~shrmkit.analysis.baselines.gaussian_lobes.GaussianLobeModel` with the
    distant viewer's map: B(R, view) evaluated on the lat-long grid of the stack's finest
    level (a renderer evaluates the lobes per pixel instead; the map is for inspection)."""

    model: GaussianLobeModel

    def radiance(self, R: np.ndarray, V: np.ndarray) -> np.ndarray:
        """B(R, V), (n, 3)."""
        return self.model.radiance(R, V)

    def view_map(self, view: np.ndarray) -> np.ndarray:
        """float32 (H, W, 3): B(R, view) at the pixel centres of the finest mip level."""
        h, w = self.model.stack.levels[0].shape[:2]
        R = pixel_directions(h, w).reshape(-1, 3)
        V = np.broadcast_to(np.asarray(view, dtype=np.float64).reshape(1, 3), R.shape)
        return self.model.radiance(R, V).reshape(h, w, 3).astype(np.float32)


def build_green_lobes(ctx: BuildContext) -> list[BuiltRepresentation]:
    """One representation per K in ``options.lobes`` (none when it is empty)."""
    opts = ctx.options
    if not opts.lobes:
        return []
    ctx.stage("Gaussian lobes: sampling")
    t0 = time.perf_counter()
    samples = gaussian_transfer_samples(ctx.brdf, opts.elevations)
    t_samples = time.perf_counter() - t0
    stack = sg_mip_stack(ctx.env)
    reps = []
    for K in opts.lobes:
        ctx.stage(f"Gaussian lobes K={K}")
        model = gaussian_lobes_model(ctx.env, ctx.brdf, lobes=K, samples=samples, stack=stack)
        fit = model.lobes
        fit_s = fit.meta["seconds"] + t_samples
        params = {"K": K, "elevations": opts.elevations, "levels": len(stack.sigmas),
                  "sigma0": float(stack.sigmas[0]), "fit_residual_max": float(fit.residual.max()),
                  "fit_s": fit_s, "mip_stack_s": stack.seconds}
        reps.append(ctx.make(f"gaussian_lobes_k{K}", f"Gaussian lobes K={K}", f"Lobes K={K}", LobeMaps(model),
                             storage_bytes=model.nbytes, precompute_s=fit_s + stack.seconds, params=params,
                             static=True))
    return reps
