"""The representations compared with the SHRM, each built once and evaluated as B(R, V).

A :class:`Representation` is a name, a radiance function ``radiance(R, V) -> (n, 3)``, and
its costs: storage in bytes, precompute seconds (everything from the BRDF and the
environment to the data a renderer uploads), and per-frame update seconds (CPU work per new
view direction before drawing, distant viewer). :func:`build_representations` makes the
set of issue 7: the SHRM at the chosen (F, P) (RH02), the SHRM at a lower P, Kautz & McCool
2000 (q = 0 terms), Cabral et al. 1999 (12 maps, from the SHRM and, optionally, by the
angular reference), and Green et al. 2007 Gaussian lobes for several K.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...brdf_io.brdf import BRDF
from ..baselines.gaussian_lobes import GaussianLobeModel, fit_gaussian_lobes, sg_mip_stack, transfer_samples
from ..baselines.rsibr import RSIBRMaps, rsibr_from_shrm, rsibr_reference
from ..shrm import SHRM, prefilter

__all__ = ["Representation", "build_representations", "time_update"]


@dataclass(frozen=True, eq=False)
class Representation:
    """One comparator: ``key`` (machine name), ``label`` (for tables), ``radiance(R, V)``,
    ``storage_bytes``, ``precompute_s``, ``update_s`` and free-form ``params``."""

    key: str
    label: str
    radiance: Callable[[np.ndarray, np.ndarray], np.ndarray]
    storage_bytes: int
    precompute_s: float
    update_s: float
    params: dict[str, Any] = field(default_factory=dict)
    model: Any = None


def time_update(fn: Callable[[], Any], repeat: int = 5) -> float:
    """Median wall time of ``repeat`` calls of ``fn`` (after one warm-up call)."""
    fn()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def _timed(fn: Callable[[], Any]) -> tuple[Any, float]:
    t0 = time.perf_counter()
    value = fn()
    return value, time.perf_counter() - t0


def _shrm_rep(key: str, label: str, shrm: SHRM, seconds: float, view: np.ndarray, *, storage: int | None = None,
              extra: dict[str, Any] | None = None) -> Representation:
    params = {"F": shrm.F, "P": shrm.P, "map": f"{shrm.height}x{shrm.width}", **(extra or {})}
    return Representation(
        key, label, shrm.radiance, int(shrm.coeffs.nbytes if storage is None else storage), seconds,
        time_update(lambda: shrm.view_map(view)), params, shrm,
    )


def _rsibr_rep(key: str, label: str, maps: RSIBRMaps, seconds: float, view: np.ndarray) -> Representation:
    h, w = maps.maps.shape[1:3]
    params = {"views": 12, "map": f"{h}x{w}", "source": maps.meta["source"]}
    return Representation(key, label, maps.radiance, maps.nbytes, seconds,
                          time_update(lambda: maps.view_map(view)), params, maps)


def build_representations(
    env: Any,
    brdf: BRDF,
    eps: float = 0.03,
    *,
    lower_P: int | None = None,
    lobes: Sequence[int] = (1, 2, 3, 4),
    n_elevations: int = 15,
    cabral_reference_height: int | None = 32,
    view: np.ndarray = (1.0, 0.0, 0.3),
    progress: Callable[[str], None] | None = None,
) -> list[Representation]:
    """Build every representation for one BRDF under one environment.

    Parameters
    ----------
    env
        EnvironmentMap (use a small one, ~64 rows: the angular reference is O(W S_L²)).
    brdf
        Any evaluable BRDF.
    eps
        SHRM tolerance; (F, P) from :func:`~shrmkit.analysis.shrm.prefilter`.
    lower_P
        P of the lower-order SHRM (default max(P − 2, 0), at least one below P when P ≥ 1).
    lobes
        Values of K for the Gaussian-lobe fits.
    n_elevations
        View elevations of the Gaussian-lobe fits.
    cabral_reference_height
        Rows of Cabral's maps computed by the angular reference (the original method's
        cost); None skips that row.
    view
        View direction used to time the per-frame updates.
    """
    def stage(name: str) -> None:
        if progress is not None:
            progress(name)

    view = np.asarray(view, dtype=np.float64)
    view = view / np.linalg.norm(view)
    reps: list[Representation] = []
    stage("SHRM")
    shrm, t_shrm = _timed(lambda: prefilter(env, brdf, eps=eps))
    reps.append(_shrm_rep("shrm", f"SHRM F={shrm.F} P={shrm.P}", shrm, t_shrm, view))
    p_low = max(shrm.P - 2, 0) if lower_P is None else int(lower_P)
    if p_low < shrm.P:
        stage(f"SHRM P={p_low}")
        low, t_low = _timed(lambda: prefilter(env, brdf, eps=eps, F=shrm.F, P=p_low, size=shrm.height))
        reps.append(_shrm_rep("shrm_low_p", f"SHRM F={low.F} P={low.P}", low, t_low, view))
    stage("Kautz-McCool")
    km, t_km = _timed(lambda: prefilter(env, brdf, eps=eps, F=shrm.F, P=shrm.P, size=shrm.height, azimuth_free=True))
    # Kautz & McCool store the P+1 local maps B_p0(α, β); the renderer is fed the global SHRM
    km_storage = (km.P + 1) * km.height * km.width * 3 * 4
    reps.append(_shrm_rep("kautz_mccool", f"Kautz-McCool q=0 P={km.P}", km, t_km, view, storage=km_storage,
                          extra={"stored_maps": km.P + 1}))
    stage("Cabral (from SHRM)")
    maps = rsibr_from_shrm(shrm)
    reps.append(_rsibr_rep("cabral_shrm", "Cabral 12 maps (SHRM)", maps, t_shrm + maps.meta["seconds"], view))
    if cabral_reference_height:
        stage("Cabral (angular reference)")
        ref_maps = rsibr_reference(env, brdf, int(cabral_reference_height))
        reps.append(_rsibr_rep("cabral_reference", "Cabral 12 maps (reference)", ref_maps,
                               ref_maps.meta["seconds"], view))
    if lobes:
        stage("Gaussian lobes: sampling")
        theta_v = np.linspace(0.0, np.radians(89.0), n_elevations)
        samples, t_samples = _timed(lambda: transfer_samples(brdf, theta_v))
        stack = sg_mip_stack(env)
        for K in lobes:
            stage(f"Gaussian lobes K={K}")
            fit = fit_gaussian_lobes(brdf, K, samples=samples)
            model = GaussianLobeModel(fit, stack)
            params = {"K": K, "elevations": n_elevations, "levels": len(stack.sigmas),
                      "sigma0": float(stack.sigmas[0]), "fit_residual_max": float(fit.residual.max()),
                      "fit_s": fit.meta["seconds"] + t_samples, "mip_stack_s": stack.seconds}
            reps.append(Representation(
                f"gaussian_k{K}", f"Gaussian lobes K={K}", model.radiance, model.nbytes,
                fit.meta["seconds"] + t_samples + stack.seconds, 0.0, params, model,
            ))
    return reps
