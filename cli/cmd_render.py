"""``shrm render``: render a mesh with the SHRM of an environment and a BRDF, offscreen."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from ..brdf_io.atomic import check_writable
from ..brdf_io.errors import BadInputError
from .common import add_env_orientation, load_env_arg

HELP = "render a mesh shaded by the SHRM of ENV and BRDF to PNG (and linear EXR), offscreen"


def _vector(text: str, option: str) -> np.ndarray:
    parts = text.split(",")
    try:
        v = np.array([float(p) for p in parts], dtype=np.float64)
    except ValueError:
        raise BadInputError(None, f"{option} must be three numbers x,y,z, got {text!r}") from None
    if v.shape != (3,) or not np.all(np.isfinite(v)) or not np.any(v):
        raise BadInputError(None, f"{option} must be three finite numbers x,y,z, not all zero, got {text!r}")
    return v


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "mesh", metavar="MESH", help="mesh file (obj, ply, stl, off, glb, gltf) or builtin:sphere|torus|torus-knot"
    )
    p.add_argument("--env", default="builtin:sky", help="environment map spec or file (default builtin:sky)")
    p.add_argument("--brdf", default="microfacet:sigma=0.2", help="BRDF spec or file (default microfacet:sigma=0.2)")
    p.add_argument("--eps", type=float, default=0.03, help="SHRM tolerance epsilon (default 0.03)")
    p.add_argument("--mode", choices=("distant", "perpixel", "rsibr", "kautz-mccool", "gaussian-lobes"),
                   default="distant",
                   help="distant viewer (RH02 eq. 12), per-pixel view direction, Cabral et al. 1999 (12 "
                        "blended maps), Kautz-McCool 2000 (q = 0 SHRM, per pixel) or Green et al. 2007 "
                        "(K Gaussian lobes per view elevation over an SG mip stack) (default distant)")
    p.add_argument("--lobes", type=int, default=3, help="gaussian-lobes: lobes per elevation K (default 3)")
    p.add_argument("--elevations", type=int, default=15,
                   help="gaussian-lobes: fitted view elevations (default 15)")
    p.add_argument("--self-shadow", action="store_true",
                   help="gaussian-lobes: per-vertex self-shadowing by ray casting (Green et al. 2007 eq. 7)")
    p.add_argument("--size", type=int, default=512, help="image width and height in pixels (default 512)")
    p.add_argument("--camera", choices=("perspective", "ortho"), default="perspective")
    p.add_argument("--view", default="1,0,0", help="direction from the object toward the camera, z-up frame")
    p.add_argument("--up", default="0,0,1", help="image up direction, z-up frame (default 0,0,1)")
    p.add_argument("--exposure", type=float, default=0.0, help="exposure in stops for the PNG (default 0)")
    p.add_argument("--tone", choices=("filmic", "srgb"), default="filmic", help="PNG tone mapping (default filmic)")
    p.add_argument("--background", choices=("env", "black", "transparent"), default="env",
                   help="environment seen behind the object, black, or transparent PNG (default env)")
    p.add_argument("--turntable", type=int, default=0, metavar="N",
                   help="render N frames around the z axis to OUT_0000.png ... and OUT.gif")
    p.add_argument("--fps-frames", type=int, default=10, help="repeated frames for the fps figure (default 10)")
    p.add_argument("-o", "--output", required=True, help="output PNG")
    add_env_orientation(p)
    p.add_argument("--exr", help="also write linear radiance (before tone mapping) to this EXR")


def run(args: argparse.Namespace) -> int:
    from ..analysis.shrm import prefilter
    from ..brdf_io.specs import load_brdf
    from ..render.camera import Camera
    from ..render.mesh import load_mesh
    from ..render.output import to_8bit, turntable_paths, write_exr, write_gif, write_png
    from ..render.pipeline import render_frames, turntable_cameras

    if not 16 <= args.size <= 8192:
        raise BadInputError(None, f"--size must be in [16, 8192], got {args.size}")
    if not (np.isfinite(args.eps) and 0.0 < args.eps < 1.0):
        raise BadInputError(None, f"--eps must be in (0, 1), got {args.eps}")
    if not np.isfinite(args.exposure):
        raise BadInputError(None, f"--exposure must be finite, got {args.exposure}")
    if args.turntable < 0 or args.fps_frames < 0:
        raise BadInputError(None, "--turntable and --fps-frames must be >= 0")
    if Path(args.output).suffix.lower() != ".png":
        raise BadInputError(args.output, "output must be a .png file")
    if args.exr and Path(args.exr).suffix.lower() != ".exr":
        raise BadInputError(args.exr, "--exr must name a .exr file")
    if not 1 <= args.lobes <= 8 or not 1 <= args.elevations <= 90:
        raise BadInputError(None, f"--lobes must be in [1, 8] and --elevations in [1, 90], got "
                                  f"{args.lobes}, {args.elevations}")
    view, up = _vector(args.view, "--view"), _vector(args.up, "--up")
    try:
        camera = Camera.looking_at(view=view, up=up, projection=args.camera)
    except ValueError as err:
        raise BadInputError(None, f"--view/--up: {err}") from None

    for path in (args.output, args.exr):
        if path:
            check_writable(path)
    mesh = load_mesh(args.mesh)
    env = load_env_arg(args.env, args)
    brdf = load_brdf(args.brdf)
    print(f"mesh {mesh.name}: {mesh.n_triangles} triangles")
    if args.self_shadow and args.mode != "gaussian-lobes":
        raise BadInputError(None, "--self-shadow needs --mode gaussian-lobes")
    visibility = None
    if args.mode == "gaussian-lobes":
        from ..analysis.baselines.gaussian_lobes import GaussianLobeModel, fit_gaussian_lobes, sg_mip_stack

        lobes = fit_gaussian_lobes(brdf, K=args.lobes, n_elevations=args.elevations)
        stack = sg_mip_stack(env)
        shrm = GaussianLobeModel(lobes, stack)
        render_mode = "gaussian-lobes"
        print(f"Gaussian lobes K={lobes.K} at {lobes.theta_v.size} elevations, max relative fit error "
              f"{float(lobes.residual.max()):.3g}")
        print(f"fit: {lobes.meta['seconds']:.3f} s")
        print(f"SG mip stack: {len(stack.levels)} levels, sigma {stack.sigmas[0]:.4g}..{stack.sigmas[-1]:.4g} rad, "
              f"{stack.seconds:.3f} s")
        if args.self_shadow:
            from ..analysis.baselines.selfshadow import vertex_visibility_sh

            t0 = time.perf_counter()
            visibility = vertex_visibility_sh(mesh)
            print(f"self-shadowing: order-4 SH visibility of {len(mesh.vertices)} vertices, "
                  f"{time.perf_counter() - t0:.3f} s")
    else:
        t0 = time.perf_counter()
        shrm = prefilter(env, brdf, eps=args.eps, azimuth_free=args.mode == "kautz-mccool")
        render_mode = "perpixel" if args.mode == "kautz-mccool" else args.mode
        t_prefilter = time.perf_counter() - t0
        print(f"SHRM F={shrm.F} P={shrm.P} on {shrm.height}x{shrm.width} (eps {args.eps:g})")
        print(f"prefilter: {t_prefilter:.3f} s")

    cameras = turntable_cameras(camera, args.turntable) if args.turntable else [camera]
    frames, timings = render_frames(
        mesh, shrm, cameras, size=args.size, mode=render_mode, env_radiance=env.radiance,
        background=args.background, fps_frames=args.fps_frames, visibility_sh=visibility,
    )
    print(f"renderer: {timings.backend}, mode {args.mode}, {args.size}x{args.size}, {args.camera}")
    print(f"first frame: {timings.first_frame_s:.3f} s")
    if timings.fps_frames:
        print(f"frames per second: {timings.fps:.1f} (over {timings.fps_frames} frames)")

    def png(frame):
        alpha = frame.alpha if frame.transparent else None
        return to_8bit(frame.linear, alpha, exposure=args.exposure, curve=args.tone)

    if args.turntable:
        pngs, gif = turntable_paths(args.output, args.turntable)
        exrs = turntable_paths(args.exr, args.turntable)[0] if args.exr else [None] * len(frames)
        images = []
        for frame, png_path, exr_path in zip(frames, pngs, exrs, strict=True):
            image = png(frame)
            images.append(image)
            write_png(png_path, image)
            if exr_path is not None:
                write_exr(exr_path, frame.linear, frame.alpha)
        write_gif(gif, images)
        print(f"wrote {pngs[0]} ... {pngs[-1]} and {gif}")
    else:
        write_png(args.output, png(frames[0]))
        print(f"wrote {args.output}")
        if args.exr:
            write_exr(args.exr, frames[0].linear, frames[0].alpha)
            print(f"wrote {args.exr} (linear radiance, channels R G B A)")
    return 0
