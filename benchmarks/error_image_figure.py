"""The README's error-image figure, and the prediction measured against brute force on its pixels (issue 23).

1. Renders the figure's scene with the command the README shows —
   ``shrm render builtin:sphere --env venice_sunset_1k.hdr --env-up y --brdf microfacet:sigma=0.1
   --mode perpixel --view 1,-0.2,0.25 --size 256 -o render.png --error-image err.exr`` — and writes
   ``docs/images/error_image_render.png`` (the render) and ``docs/images/error_image_error.png`` (the
   error image in false colour, log scale 0.1 %–100 %, ``render.error_image.false_colour``, with a
   colour bar; white: no object).
2. Measures the prediction on the figure's own pixels: ``--pixels`` covered pixels drawn at random
   (seeded), each pixel's R as the renderer's shaders compute it and V from the camera
   (``render.error_image.pixel_directions``), the brute-force angular reference
   (``analysis.reference.reference_radiance``, every pixel of the 512 × 1024 map) and the same SHRM
   (``prefilter`` is deterministic): measured relative error |SHRM.radiance − reference| / |reference|
   per pixel (channel-RMS norms) against the value of the error image at that pixel and the bound
   version (``predicted_error(bound=True)``). About 0.1 s per pixel on one core of this machine.

Run from the repository root:

    .venv/bin/python benchmarks/error_image_figure.py [--pixels 1024] [--seed 0] [--out docs/images]
                                                      [--no-measure]

Reads ``/work/shared/data/env/polyhaven_cc0/venice_sunset_1k.hdr`` (CC0, Poly Haven); writes only the
two PNGs (each < 200 kB) and prints the numbers.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import LinearSegmentedColormap, LogNorm  # noqa: E402
from PIL import Image  # noqa: E402
from scipy.stats import spearmanr  # noqa: E402

from shrmkit.analysis.error_image import channel_norm, predicted_error, view_angle  # noqa: E402
from shrmkit.analysis.reference import reference_radiance  # noqa: E402
from shrmkit.analysis.shrm import prefilter  # noqa: E402
from shrmkit.brdf_io.envmap import load_env  # noqa: E402
from shrmkit.brdf_io.exr import read_exr  # noqa: E402
from shrmkit.brdf_io.specs import load_brdf  # noqa: E402
from shrmkit.cli.main import main as shrm_main  # noqa: E402
from shrmkit.render.camera import Camera  # noqa: E402
from shrmkit.render.error_image import FALSE_COLOUR_RANGE, _colour_map, false_colour, pixel_directions  # noqa: E402
from shrmkit.render.mesh import load_mesh  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
ENV = Path(__file__).resolve().parents[2] / "shared" / "data" / "env" / "polyhaven_cc0" / "venice_sunset_1k.hdr"
BRDF = "microfacet:sigma=0.1"
VIEW = (1.0, -0.2, 0.25)
MESH = "builtin:sphere"


def render_command(env: Path, size: int, png: Path, err: Path) -> list[str]:
    return ["render", MESH, "--env", str(env), "--env-up", "y", "--brdf", BRDF, "--mode", "perpixel",
            "--view", ",".join(f"{v:g}" for v in VIEW), "--size", str(size), "--fps-frames", "0",
            "-o", str(png), "--error-image", str(err)]


def figure(error: np.ndarray, path: Path) -> None:
    """The error image in false colour beside a log colour bar, about the render's pixel size."""
    size = error.shape[0]
    dpi = 100
    fig = plt.figure(figsize=((size + 110) / dpi, (size + 16) / dpi), dpi=dpi)
    ax = fig.add_axes((8 / (size + 110), 8 / (size + 16), size / (size + 110), size / (size + 16)))
    ax.imshow(false_colour(error), interpolation="nearest")
    ax.set_axis_off()
    cax = fig.add_axes(((size + 24) / (size + 110), 0.12, 12 / (size + 110), 0.76))
    cmap = LinearSegmentedColormap.from_list("shrm_error", _colour_map(np.linspace(0.0, 1.0, 256)))
    bar = fig.colorbar(plt.cm.ScalarMappable(norm=LogNorm(*FALSE_COLOUR_RANGE), cmap=cmap), cax=cax)
    bar.set_label("predicted relative error", fontsize=8)
    bar.ax.tick_params(labelsize=7)
    fig.savefig(path, dpi=dpi, facecolor="white")
    plt.close(fig)


def measure(env_path: Path, size: int, error: np.ndarray, n_pixels: int, seed: int) -> None:
    env = load_env(env_path, up="y")
    brdf = load_brdf(BRDF)
    shrm = prefilter(env, brdf, eps=0.03)
    camera = Camera.looking_at(view=VIEW)
    R, V, covered = pixel_directions(load_mesh(MESH), shrm, camera, size)
    rows, cols = np.nonzero(covered & np.isfinite(error))
    pick = np.random.default_rng(seed).choice(rows.size, size=min(n_pixels, rows.size), replace=False)
    rows, cols = rows[pick], cols[pick]
    R, V = R[rows, cols], V[rows, cols]
    predicted = error[rows, cols].astype(np.float64)
    again = predicted_error(shrm, R, V)
    print(f"SHRM F={shrm.F} P={shrm.P}, lights {len(shrm.lights) if shrm.has_lights else 0} samples; "
          f"image vs recomputed prediction: max relative difference {np.max(np.abs(again / predicted - 1)):.2g}")
    bound = predicted_error(shrm, R, V, bound=True)
    t0 = time.perf_counter()
    reference = reference_radiance(env, brdf, R, V)
    print(f"brute force on {R.shape[0]} pixels: {time.perf_counter() - t0:.1f} s")
    measured = channel_norm(shrm.radiance(R, V) - reference) / channel_norm(reference)
    ratio = measured / predicted
    print(f"measured   median {np.median(measured):.3g}  90th pct {np.percentile(measured, 90):.3g}")
    print(f"predicted  median {np.median(predicted):.3g}  90th pct {np.percentile(predicted, 90):.3g}")
    print(f"measured/predicted per pixel: median {np.median(ratio):.3g}, 90th pct {np.percentile(ratio, 90):.3g}, "
          f"99th pct {np.percentile(ratio, 99):.3g}; Spearman rank correlation {spearmanr(predicted, measured)[0]:.3f}")
    print(f"bound version (level 10 %) >= measured on {100 * np.mean(bound >= measured):.1f} % of the pixels")
    theta = view_angle(R, V)
    edges = [0, 30, 60, 75, 90]
    print("by view angle: theta_v  pixels  measured median  predicted median  ratio median")
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        sel = (theta >= lo) & (theta < hi)
        if sel.any():
            print(f"  {lo:2d}-{hi:2d}  {sel.sum():6d}  {np.median(measured[sel]):15.3g}  "
                  f"{np.median(predicted[sel]):16.3g}  {np.median(ratio[sel]):12.3g}")


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--pixels", type=int, default=1024, help="pixels measured against brute force (default 1024)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--size", type=int, default=256, help="image size (default 256, the README's)")
    p.add_argument("--out", type=Path, default=ROOT / "docs" / "images", help="folder of the two PNGs")
    p.add_argument("--no-measure", action="store_true", help="only make the figure")
    args = p.parse_args(argv)
    if not ENV.is_file():
        print(f"{ENV} not found: the figure needs the shared data")
        return 1
    with tempfile.TemporaryDirectory() as tmp:
        png, err = Path(tmp) / "render.png", Path(tmp) / "err.exr"
        command = render_command(ENV, args.size, png, err)
        print("shrm " + " ".join(command))
        if shrm_main(command) != 0:
            return 1
        error = read_exr(err)[..., 0]
        args.out.mkdir(parents=True, exist_ok=True)
        Image.open(png).save(args.out / "error_image_render.png", optimize=True)
        figure(error, args.out / "error_image_error.png")
    for name in ("error_image_render.png", "error_image_error.png"):
        print(f"wrote {args.out / name} ({(args.out / name).stat().st_size / 1024:.0f} kB)")
    if not args.no_measure:
        measure(ENV, args.size, error, args.pixels, args.seed)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
