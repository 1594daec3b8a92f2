"""pbrt-v4 ``coateddiffuse`` against the conductor ``mix`` for diffuse + dielectric-like models (issue 26).

    .venv/bin/python benchmarks/export_pbrt_coated.py            # ~30 s CPU
    .venv/bin/python benchmarks/export_pbrt_coated.py --quick    # 4 models

For each Cook–Torrance model with a diffuse term and a dielectric-like lobe (ks·f0 ≤ 0.25), both
pbrt-v4 materials ``shrm export`` can write are built (``brdf_io/export_material.py``:
``_pbrt_mix``, ``_pbrt_coated``) and their measured error against the model is printed (relative
RMS of ρ cos θ_i, all views / worst view band, 16384 Sobol pairs with θ ≤ 80°, as
``analysis/material_export.py`` states it), with the material ``to_target`` chooses, the coat's
η, base reflectance, ``maxdepth``, and the CPU seconds of the export. The coated material is
evaluated by ``brdf_io/pbrt_coated.py``'s closed form of pbrt-v4's random walk (no medium, thin
layer); pbrt itself is not run here.

(b) The closed form's layered part (the base seen through the coat) against pbrt-v4's
``LayeredBxDF::f`` estimator transcribed to numpy (``DielectricBxDF::Sample_f``/``f``/``PDF``,
``TrowbridgeReitzDistribution::Sample_wm``, Russian roulette, both next-event estimates with
pbrt's power-heuristic weights), and the same walk with matched MIS densities.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from shrmkit.analysis.material_export import export_material
from shrmkit.brdf_io import export_material as em
from shrmkit.brdf_io.specs import brdf_from_spec

MODELS = [
    "cook-torrance:kd=0.3/0.2/0.1,ks=1,alpha=0.05,f0=0.04,dist=ggx",
    "cook-torrance:kd=0.3/0.2/0.1,ks=1,alpha=0.2,f0=0.04,dist=ggx",
    "cook-torrance:kd=0.3/0.2/0.1,ks=1,alpha=0.5,f0=0.04,dist=ggx",
    "cook-torrance:kd=0.6/0.5/0.4,ks=1,alpha=0.2,f0=0.04,dist=ggx",
    "cook-torrance:kd=0.8/0.8/0.8,ks=1,alpha=0.2,f0=0.04,dist=ggx",
    "cook-torrance:kd=0.3/0.2/0.1,ks=1,alpha=0.2,f0=0.1,dist=ggx",
    "cook-torrance:kd=0.3/0.2/0.1,ks=1,alpha=0.3,f0=0.04,dist=beckmann",
    "cook-torrance:kd=0.3/0.2/0.1,ks=0.5,alpha=0.3,f0=0.04,dist=beckmann",
    "cook-torrance:kd=0.3/0.2/0.1,ks=0.5,alpha=0.2,f0=0.04,dist=ggx",
    "cook-torrance:kd=0.05,ks=1,alpha=0.2,f0=0.04,dist=ggx",
]


def _forced(builder):
    """``to_target(…, "pbrt")`` with the choice fixed to one builder (for the comparison only)."""
    def convert(brdf):
        kd = np.asarray(brdf.kd, float) * np.ones(3)
        ks, f0 = np.asarray(brdf.ks, float) * np.ones(3), np.asarray(brdf.f0, float) * np.ones(3)
        return builder(brdf.to_spec(), kd, brdf, ks, f0)
    return convert


# ---------------------------------------------------------------------------------------------
# (b) pbrt-v4's LayeredBxDF::f estimator, transcribed (reflection, no medium, two-sided top entry)
# ---------------------------------------------------------------------------------------------
def _norm(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.where(n > 0, n, 1.0)


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.sum(a * b, axis=-1)


def _fr(cos_i: np.ndarray, eta: float) -> np.ndarray:
    """FrDielectric."""
    c = np.clip(cos_i, -1, 1)
    e = np.where(c < 0, 1 / eta, eta)
    c = np.abs(c)
    s2 = (1 - c * c) / e**2
    ct = np.sqrt(np.maximum(0, 1 - s2))
    return np.where(s2 >= 1, 1.0, (((e * c - ct) / (e * c + ct)) ** 2 + ((c - e * ct) / (c + e * ct)) ** 2) / 2)


class _TR:
    """TrowbridgeReitzDistribution (isotropic)."""

    def __init__(self, alpha: float):
        self.a = alpha

    def lam(self, w):
        c2 = w[..., 2] ** 2
        t2 = np.where(c2 > 0, (1 - c2) / np.maximum(c2, 1e-300), np.inf)
        return np.where(np.isinf(t2), 0.0, (np.sqrt(1 + self.a**2 * np.where(np.isinf(t2), 0, t2)) - 1) / 2)

    def D(self, wm):
        c2 = wm[..., 2] ** 2
        t2 = (1 - c2) / np.maximum(c2, 1e-300)
        return np.where(c2 > 0, 1 / (np.pi * self.a**2 * c2 * c2 * (1 + t2 / self.a**2) ** 2), 0.0)

    def G1(self, w):
        return 1 / (1 + self.lam(w))

    def G(self, wo, wi):
        return 1 / (1 + self.lam(wo) + self.lam(wi))

    def pdf(self, w, wm):  # D(w, wm), the visible normal density
        return self.G1(w) / np.abs(w[..., 2]) * self.D(wm) * np.abs(_dot(w, wm))

    def sample_wm(self, w, u):
        a = self.a
        wh = _norm(np.stack([a * w[..., 0], a * w[..., 1], w[..., 2]], -1))
        wh = wh * np.where(wh[..., 2:] < 0, -1, 1)
        t1 = np.where(wh[..., 2:] < 0.99999, _norm(np.cross([0.0, 0.0, 1.0], wh) + 1e-300), [1.0, 0.0, 0.0])
        t2 = np.cross(wh, t1)
        r, th = np.sqrt(u[..., 0]), 2 * np.pi * u[..., 1]
        px, py = r * np.cos(th), r * np.sin(th)
        h = np.sqrt(1 - px * px)
        t = (1 + wh[..., 2]) / 2
        py = (1 - t) * h + t * py
        pz = np.sqrt(np.maximum(0, 1 - px * px - py * py))
        nh = px[..., None] * t1 + py[..., None] * t2 + pz[..., None] * wh
        return _norm(np.stack([a * nh[..., 0], a * nh[..., 1], np.maximum(1e-6, nh[..., 2])], -1))


def _refract(wi, n, eta):
    c = _dot(n, wi)
    flip = c < 0
    e = np.where(flip, 1 / eta, eta)
    n = np.where(flip[..., None], -n, n)
    c = np.abs(c)
    s2t = np.maximum(0, 1 - c * c) / e**2
    ct = np.sqrt(np.maximum(0, 1 - s2t))
    wt = -wi / e[..., None] + (c / e - ct)[..., None] * n
    return s2t < 1, e, wt


def _top_f(wo, wi, eta, tr, radiance):
    """DielectricBxDF::f."""
    co, ci = wo[..., 2], wi[..., 2]
    reflect = ci * co > 0
    etap = np.where(reflect, 1.0, np.where(co > 0, eta, 1 / eta))
    wm = wi * etap[..., None] + wo
    n = np.linalg.norm(wm, axis=-1, keepdims=True)
    wm = wm / np.where(n > 0, n, 1)
    wm = wm * np.where(wm[..., 2:] < 0, -1, 1)
    di, do = _dot(wm, wi), _dot(wm, wo)
    ok = (ci != 0) & (co != 0) & (n[..., 0] > 0) & (di * ci >= 0) & (do * co >= 0)
    F = _fr(do, eta)
    D, G = tr.D(wm), tr.G(wo, wi)
    fr = D * G * F / np.abs(4 * ci * co)
    denom = (di + do / etap) ** 2 * ci * co
    ft = D * (1 - F) * G * np.abs(di * do / np.where(denom != 0, denom, 1))
    ft = ft / etap**2 if radiance else ft
    return np.where(ok, np.where(reflect, fr, ft), 0.0)


def _top_pdf_t(wo, wi, eta, tr):
    """DielectricBxDF::PDF with BxDFReflTransFlags::Transmission (wo, wi on opposite sides)."""
    co = wo[..., 2]
    etap = np.where(co > 0, eta, 1 / eta)
    wm = wi * etap[..., None] + wo
    n = np.linalg.norm(wm, axis=-1, keepdims=True)
    wm = wm / np.where(n > 0, n, 1)
    wm = wm * np.where(wm[..., 2:] < 0, -1, 1)
    di, do = _dot(wm, wi), _dot(wm, wo)
    ok = (wi[..., 2] * co < 0) & (n[..., 0] > 0) & (di * wi[..., 2] >= 0) & (do * co >= 0)
    T = 1 - _fr(do, eta)
    pdf = tr.pdf(wo, wm) * np.abs(di) / (di + do / etap) ** 2
    return np.where(ok & (T > 0), pdf, 0.0)


def _top_sample(wo, u, eta, tr, radiance, transmission):
    """DielectricBxDF::Sample_f restricted to transmission or to reflection: (ok, f, wi, pdf)."""
    wm = tr.sample_wm(wo, u)
    R = _fr(_dot(wo, wm), eta)
    if transmission:
        valid, etap, wi = _refract(wo, wm, eta)
        ok = valid & (wo[..., 2] * wi[..., 2] < 0) & (wi[..., 2] != 0) & (1 - R > 0)
        denom = (_dot(wi, wm) + _dot(wo, wm) / etap) ** 2
        pdf = tr.pdf(wo, wm) * np.abs(_dot(wi, wm)) / denom
        f = (1 - R) * tr.D(wm) * tr.G(wo, wi) * np.abs(_dot(wi, wm) * _dot(wo, wm) / (wi[..., 2] * wo[..., 2] * denom))
        f = f / etap**2 if radiance else f
    else:
        wi = -wo + 2 * _dot(wo, wm)[..., None] * wm
        ok = (wo[..., 2] * wi[..., 2] > 0) & (R > 0)
        pdf = tr.pdf(wo, wm) / (4 * np.abs(_dot(wo, wm)))
        f = tr.D(wm) * tr.G(wo, wi) * R / (4 * wi[..., 2] * wo[..., 2])
    ok = ok & (pdf > 0) & (f > 0)
    return ok, np.where(ok, f, 0.0), wi, np.where(ok, pdf, 1.0)


def layered_f(wo, wi, *, alpha, eta, R, thickness, maxdepth, n, rng, matched=False):
    """pbrt-v4 LayeredBxDF<DielectricBxDF, DiffuseBxDF>::f(wo, wi) (albedo 0, wo and wi above),
    estimated with ``n`` independent walks; returns (mean, standard error) of the layered part
    (without the top's own reflection, which pbrt adds exactly). pbrt weighs its second
    next-event estimate with ``exitInterface.PDF(-w, wi)``, the density of wi given the base's
    direction, where the first strategy's density of that direction is ``PDF(wi, -w)``: the two
    MIS weights then need not sum to one. ``matched`` uses ``PDF(wi, -w)`` (an unbiased walk)."""
    tr = _TR(alpha)
    woN, wiN = np.broadcast_to(wo, (n, 3)), np.broadcast_to(wi, (n, 3))
    contrib = np.zeros(n)

    def Tr(w):
        return np.exp(-np.abs(thickness / w[..., 2]))

    ok_o, f_o, w, pdf_o = _top_sample(woN, rng.random((n, 2)), eta, tr, True, True)  # wos (radiance)
    ok_i, f_i, wis_wi, pdf_i = _top_sample(wiN, rng.random((n, 2)), eta, tr, False, True)  # wis (importance)
    alive = ok_o & ok_i
    beta = np.where(alive, f_o * np.abs(w[..., 2]) / pdf_o, 0.0)
    z_top = np.ones(n, bool)  # z == thickness (entered the top)
    for depth in range(maxdepth):
        if depth > 3:
            rr = alive & (beta < 0.25)
            q = np.maximum(0, 1 - beta)
            kill = rr & (rng.random(n) < q)
            alive &= ~kill
            beta = np.where(rr & alive, beta / np.where(1 - q > 0, 1 - q, 1), beta)
        z_top = ~z_top
        beta = beta * Tr(w)
        at_top = z_top  # z == exitZ (thickness): reflect inside the coat
        if np.any(alive & at_top):
            ok, f, wn, pdf = _top_sample(-w, rng.random((n, 2)), eta, tr, True, False)
            upd = alive & at_top
            alive = np.where(upd, ok, alive)
            beta = np.where(upd & ok, beta * f * np.abs(wn[..., 2]) / pdf, beta)
            w = np.where((upd & ok)[..., None], wn, w)
        bot = alive & ~z_top
        if np.any(bot):
            # NEE along the presampled wis: wt = PowerHeuristic(wis.pdf, diffuse pdf)
            cos_wis = np.abs(wis_wi[..., 2])
            p_diff = cos_wis / np.pi
            wt = pdf_i**2 / (pdf_i**2 + p_diff**2)
            contrib += np.where(bot, beta * R / np.pi * cos_wis * wt * Tr(wis_wi) * f_i / pdf_i, 0.0)
            # sample the diffuse base (cosine), then NEE through the exit along it
            u = rng.random((n, 2))
            r, ph = np.sqrt(u[:, 0]), 2 * np.pi * u[:, 1]
            wn = np.stack([r * np.cos(ph), r * np.sin(ph), np.sqrt(np.maximum(0, 1 - r * r))], -1)
            wn[:, 2] *= np.where(-w[:, 2] < 0, -1, 1)
            pdf_b = np.abs(wn[:, 2]) / np.pi
            ok_b = bot & (pdf_b > 0)
            beta = np.where(ok_b, beta * R, beta)  # f cos/pdf = R
            alive = np.where(bot, ok_b, alive)
            w = np.where(bot[..., None], wn, w)
            f_exit = _top_f(-w, wiN, eta, tr, True)
            p_exit = _top_pdf_t(wiN, -w, eta, tr) if matched else _top_pdf_t(-w, wiN, eta, tr)
            wt = pdf_b**2 / (pdf_b**2 + p_exit**2)
            contrib += np.where(ok_b & (f_exit > 0), beta * Tr(w) * f_exit * wt, 0.0)
    return float(contrib.mean()), float(contrib.std() / np.sqrt(n))


def random_walk_check(quick: bool) -> None:
    """The closed form's layered part against the transcribed estimator."""
    from shrmkit.brdf_io.pbrt_coated import DielectricCoat

    rng = np.random.default_rng(7)
    n = 50_000 if quick else 200_000
    print(f"\n(b) layered part of f (base through the coat), closed form vs pbrt-v4's LayeredBxDF::f transcribed "
          f"({n} walks a pair, thickness 1e-4): with pbrt's MIS weights, and with matched densities")
    print(f"{'alpha':>5s} {'eta':>5s} {'R':>4s} {'th_i':>5s} {'th_o':>5s} {'dphi':>5s} {'closed form':>11s} "
          f"{'pbrt walk':>9s} {'+-':>7s} {'closed/walk-1':>13s} "
          f"{'matched walk':>12s} {'+-':>7s} {'closed/walk-1':>13s}")
    cases = [(0.05, 1.5, 0.6), (0.2, 1.44, 0.6), (0.5, 1.44, 0.8)]
    pairs = [(0, 30, 0), (30, 60, 90), (60, 75, 180), (80, 20, 45)]
    for alpha, eta, R in cases[:2] if quick else cases:
        coat = DielectricCoat.make(alpha, eta, np.full(3, R))
        for ti, to, dphi in pairs[:2] if quick else pairs:
            ti_r, to_r, dp = np.radians([ti, to, dphi])
            L = np.array([np.sin(ti_r), 0, np.cos(ti_r)])
            V = np.array([np.sin(to_r) * np.cos(dp), np.sin(to_r) * np.sin(dp), np.cos(to_r)])
            top = _top_f(V[None], L[None], eta, _TR(alpha), True)[0]
            closed = float(coat.eval(L, V)[0]) - top
            cells = []
            for matched in (False, True):
                walk, se = layered_f(V, L, alpha=alpha, eta=eta, R=R, thickness=1e-4, maxdepth=coat.maxdepth(),
                                     n=n, rng=rng, matched=matched)
                cells.append(f"{walk:9.5f} {se:7.5f} {closed / walk - 1:+13.4f}")
            print(f"{alpha:5.2f} {eta:5.2f} {R:4.1f} {ti:5d} {to:5d} {dphi:5d} {closed:11.5f} {cells[0]} "
                  f"{cells[1]:>34s}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="4 models")
    args = parser.parse_args()
    models = MODELS[:3] + MODELS[7:8] if args.quick else MODELS
    print(f"{'model':66s} {'chosen':>13s} {'mix all/worst':>14s} {'coated all/worst':>17s} "
          f"{'eta':>6s} {'reflectance':>20s} {'maxdepth':>8s} {'CPU s':>6s}")
    original = em.MATERIAL_TARGETS["pbrt"]
    for spec in models:
        brdf = brdf_from_spec(spec)
        t = time.process_time()
        chosen = export_material(brdf, "pbrt")
        seconds = time.process_time() - t
        rows = {}
        for name, builder in (("mix", em._pbrt_mix), ("coated", em._pbrt_coated)):
            em.MATERIAL_TARGETS["pbrt"] = em.MaterialTarget("pbrt", ".pbrt", _forced(builder), original.text, "")
            try:
                rows[name] = export_material(brdf, "pbrt")
            finally:
                em.MATERIAL_TARGETS["pbrt"] = original
        coat = rows["coated"].material.coat
        assert coat is not None
        print(f"{spec:66s} {chosen.material.native['type']:>13s} "
              f"{rows['mix'].rel_rms:6.3f}/{rows['mix'].worst.rel_rms:6.3f} "
              f"{rows['coated'].rel_rms:8.3f}/{rows['coated'].worst.rel_rms:6.3f} {coat.eta:6.3f} "
              f"{' '.join(f'{r:.3f}' for r in coat.reflectance):>20s} {coat.maxdepth():8d} {seconds:6.2f}")
    random_walk_check(args.quick)


if __name__ == "__main__":
    main()
