"""``shrm render``: render a mesh with the SHRM of an environment and a BRDF, offscreen.

Parse and check the options, load the mesh and the (oriented) environment, call
:func:`shrmkit.render.api.render_scene`, print what it built and how long it took, write
the PNG/EXR/GIF files. The parser is ``options_render.py``: the modes and their help come from
the render-mode table (``shrmkit.render.modes``, through ``render.defaults``).
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..analysis.notebook import stated_band
from ..analysis.order_rule import OrderRule
from ..analysis.tolerance import check_eps
from ..brdf_io.atomic import atomic_paths, check_writable
from ..brdf_io.errors import BadInputError
from ..brdf_io.limits import check_memory
from ..render.api import SIZE_RANGE, SceneRender, SequenceRender, render_scene, render_sequence
from ..render.camera import Camera
from ..render.defaults import LOBE_OPTION_MODES
from ..render.error_image import check_error_image_request, error_image, write_error_image_line
from ..render.mesh import load_mesh
from ..render.modes import (
    RenderOptions,
    self_shadow_modes,
)
from ..render.offscreen import skipped_window_classes
from ..render.output import to_8bit, turntable_paths, write_exr, write_gif, write_png
from ..render.pipeline import Frame, light_turntable_rotations, turntable_cameras
from ..render.preview import preview_exposure
from .common import (
    ERROR_IMAGE_TERMS,
    env_rotation_arg,
    env_sources_arg,
    in_cli_terms,
    load_analysis_brdf,
    load_env_arg,
    load_env_sequence,
    order_rule,
    print_json,
    say,
)


def _vector(text: str, option: str) -> np.ndarray:
    parts = text.split(",")
    try:
        v = np.array([float(p) for p in parts], dtype=np.float64)
    except ValueError:
        raise BadInputError(None, f"{option} must be three numbers x,y,z, got {text!r}") from None
    if v.shape != (3,) or not np.all(np.isfinite(v)) or not np.any(v):
        raise BadInputError(None, f"{option} must be three finite numbers x,y,z, not all zero, got {text!r}")
    return v


def _validate(args: argparse.Namespace, sequence: bool = False) -> tuple[list[Camera], RenderOptions]:
    """Check every option before any long computation; returns the cameras and the builders' options.
    ``sequence``: ``--env`` named several maps (one frame each)."""
    lo, hi = SIZE_RANGE
    if not lo <= args.size <= hi:
        raise BadInputError(None, f"--size must be in [{lo}, {hi}], got {args.size}")
    # memory plan (data_specs/limits.md): 190-260 B a pixel measured at 1024-2048 px (8192 px: ~13 GB)
    check_memory(f"--size {args.size}", 256 * args.size**2, f"a {args.size} x {args.size} render")
    check_eps(args.eps, "--eps")
    if args.exposure is not None and not np.isfinite(args.exposure):
        raise BadInputError(None, f"--exposure must be finite, got {args.exposure}")
    if args.turntable < 0 or args.fps_frames < 0 or args.light_turntable < 0:
        raise BadInputError(None, "--turntable, --light-turntable and --fps-frames must be >= 0")
    if args.turntable and args.light_turntable:
        raise BadInputError(None, "--turntable (the camera turns) and --light-turntable (the lighting turns): "
                            "choose one")
    if sequence and (args.turntable or args.light_turntable or args.error_image):
        raise BadInputError(None, "several --env maps render one frame per map: --turntable, --light-turntable "
                            "and --error-image apply to one map")
    rotation: np.ndarray | list[np.ndarray] | None  # one rotation, or one per frame (--light-turntable)
    rotation = env_rotation_arg(args.env_rotation) if args.env_rotation is not None else None
    if Path(args.output).suffix.lower() != ".png":
        raise BadInputError(args.output, "output must be a .png file")
    if args.exr and Path(args.exr).suffix.lower() != ".exr":
        raise BadInputError(args.exr, "--exr must name a .exr file")
    if args.error_image:
        try:
            check_error_image_request(args.error_image, args.mode)
        except BadInputError as err:
            raise BadInputError(err.source, in_cli_terms(err.problem, ERROR_IMAGE_TERMS)) from None
    if args.self_shadow and args.mode not in self_shadow_modes():
        raise BadInputError(None, f"--self-shadow needs --mode {' or '.join(self_shadow_modes())}")
    given = [f"--{name}" for name in ("lobes", "elevations") if getattr(args, f"{name}_given", False)]
    if given and args.mode not in LOBE_OPTION_MODES:
        raise BadInputError(
            None, f"{' and '.join(given)} apply only to --mode {' or '.join(LOBE_OPTION_MODES)} "
            f"(the Gaussian-lobe fit), not to --mode {args.mode}",
        )
    view, up = _vector(args.view, "--view"), _vector(args.up, "--up")
    try:
        camera = Camera.looking_at(view=view, up=up, projection=args.camera)
    except ValueError as err:
        raise BadInputError(None, f"--view/--up: {err}") from None
    cameras = turntable_cameras(camera, args.turntable) if args.turntable else [camera]
    if args.light_turntable:
        cameras = [camera] * args.light_turntable
        rotation = light_turntable_rotations(args.light_turntable, rotation)
    # RenderOptions checks --lobes/--elevations (its ranges, one home) before anything is loaded
    options = RenderOptions(lobes=args.lobes, elevations=args.elevations, self_shadow=args.self_shadow,
                            window=args.window, lights=args.lights, pixel_rule=args.pixel_rule == "on",
                            env_rotation=rotation, rule=OrderRule(eps=args.eps, **order_rule(args)))
    return cameras, options


def _report(args: argparse.Namespace, result: SceneRender) -> None:
    timings = result.timings
    say(f"mesh {result.mesh.name}: {result.mesh.n_triangles} triangles")
    for line in result.built.description:
        say(line)
    skipped = "".join(f"; {name} skipped: {why}" for name, why in skipped_window_classes()
                      if name != timings.backend)
    say(f"renderer: {timings.backend}, mode {result.mode}, {args.size}x{args.size}, {args.camera}{skipped}")
    say(f"first frame: {timings.first_frame_s:.3f} s")
    if timings.fps_frames:
        say(f"frames per second: {timings.fps:.1f} (over {timings.fps_frames} frames)")
    if args.light_turntable:
        built = _build_seconds(result.built.info)
        again = "" if built is None else (
            f"; built once in {built:.3f} s = {built / timings.later_frame_s:.3g} frames "
            f"(building anew per frame would cost {args.light_turntable * built:.3f} s)")
        say(f"light turntable: {args.light_turntable} frames, {1e3 * timings.later_frame_s:.1f} ms per frame "
            f"after the first (view-time rotation, per-frame map, draw, readback, background){again}")


def _build_seconds(info: dict) -> float | None:
    """Seconds the mode's model took to build (the SHRM's prefilter; the lobes' fit and mip stack)."""
    if "prefilter_seconds" in info:
        return float(info["prefilter_seconds"]) + float(info.get("rsibr_seconds", 0.0))
    if "fit_seconds" in info:
        return float(info["fit_seconds"]) + float(info.get("mip_seconds", 0.0))
    return None


def _stated_error(info: dict) -> str:
    """The error an SHRM states for itself (``BuiltModel.info``): the worst view band's predicted and
    bounded relative RMS inside the view limit, and the per-pixel 90th percentile."""
    bands = [b for b in info.get("view_bands", []) if b["inside"]]
    if not bands:
        return "no stated error"
    worst = max(bands, key=lambda b: b["predicted_rel_rms"])
    text = (f"stated relative RMS {worst['predicted_rel_rms']:.3g} (bound {worst['bound_rel_rms']:.3g}) in the worst "
            f"view band to {info['max_view_deg']:g} degrees")
    p90 = (info.get("pixel_errors") or {}).get("p90")
    return text + ("" if p90 is None else f", per pixel p90 {p90:.3g}")


def _report_sequence(args: argparse.Namespace, seq: SequenceRender) -> None:
    """Per map: its prefilter cost beside the error stated for it; then the sequence's totals."""
    first = seq.renders[0]
    say(f"mesh {first.mesh.name}: {first.mesh.n_triangles} triangles")
    say(f"renderer: {first.timings.backend}, mode {first.mode}, {args.size}x{args.size}, {args.camera}")
    n = len(seq.renders)
    if seq.orders is not None:
        say(f"orders: F={seq.orders.F} P={seq.orders.P} of the BRDF chosen once in {seq.orders_seconds:.3f} s "
            f"for {n} maps")
    builds = []
    for k, (result, name, seconds) in enumerate(zip(seq.renders, seq.environments, seq.frame_seconds, strict=True)):
        info = result.built.info
        built = _build_seconds(info)
        builds.append(built)
        model = (f"SHRM F_B={info['F']} P={info['P']} on {info['height']}x{info['width']}" if "F" in info
                 else result.built.description[0])
        cost = "" if built is None else f"prefilter {built:.3f} s, "
        lights = (info.get("lights") or {}).get("count", 0)
        say(f"frame {k:04d} {name}: {model}, {cost}"
            f"{_stated_error(info)}{f', {lights} light(s)' if lights else ''}; frame total {seconds:.3f} s")
    known = [b for b in builds if b is not None]
    if known:
        mean = sum(known) / len(known)
        say(f"environment sequence: {n} maps, prefilter {mean:.3f} s per map (min {min(known):.3f}, max "
            f"{max(known):.3f}), {sum(seq.frame_seconds) / n:.3f} s per frame with the render"
            + ("" if seq.orders is None else f"; the order choice ({seq.orders_seconds:.3f} s) paid once"))


def _write(args: argparse.Namespace, frames: list[Frame], n_frames: int | None = None) -> list[str]:
    """Write the PNG (and EXR, GIF) files; print a line per output unless ``--json``; return the paths."""
    def png(frame: Frame) -> np.ndarray:
        alpha = frame.alpha if frame.transparent else None
        return to_8bit(frame.linear, alpha, exposure=args.exposure, curve=args.tone)

    # every output of one command is written together (atomic_paths): a full disk or a failing writer
    # leaves none of them, and the error names the file
    n_frames = n_frames or args.turntable or args.light_turntable
    if n_frames:
        pngs, gif = turntable_paths(args.output, n_frames)
        exrs = turntable_paths(args.exr, n_frames)[0] if args.exr else []
        images = [png(frame) for frame in frames]
        with atomic_paths([*pngs, *exrs, gif]) as temps:
            png_temps, exr_temps, gif_temp = temps[: len(pngs)], temps[len(pngs) : -1], temps[-1]
            for image, tmp in zip(images, png_temps, strict=True):
                write_png(tmp, image, atomic=False)
            if exr_temps:
                for frame, tmp in zip(frames, exr_temps, strict=True):
                    write_exr(tmp, frame.linear, frame.alpha, atomic=False)
            write_gif(gif_temp, images, atomic=False)
        if not args.json:
            say(f"wrote {pngs[0]} ... {pngs[-1]} and {gif}")
        return [str(p) for p in (*pngs, *exrs, gif)]
    with atomic_paths([args.output, *([args.exr] if args.exr else [])]) as temps:
        write_png(temps[0], png(frames[0]), atomic=False)
        if args.exr:
            write_exr(temps[1], frames[0].linear, frames[0].alpha, atomic=False)
    if not args.json:
        say(f"wrote {args.output}")
        if args.exr:
            say(f"wrote {args.exr} (linear radiance, channels R G B A)")
    return [str(args.output), *([str(args.exr)] if args.exr else [])]


def _model_record(info: dict, description: Sequence[str]) -> dict:
    """The JSON record of a built model: the SHRM's orders, map size, stated error (the worst view
    band inside the limit, and every band), window, lights, build seconds; other modes' ``info``."""
    if "F" not in info:
        return {"description": list(description), "info": info, "build_seconds": _build_seconds(info)}
    bands = info.get("view_bands") or []
    return {
        "F": info["F"], "P": info["P"], "height": info["height"], "width": info["width"], "eps": info["eps"],
        "criterion": info.get("criterion"), "max_view_deg": info.get("max_view_deg"),
        "stated_error": stated_band({"view_bands": bands}), "view_bands": bands,
        "pixel_errors": info.get("pixel_errors"), "window": info.get("window"),
        "lights": (info.get("lights") or {}).get("count", 0), "build_seconds": _build_seconds(info),
        "description": list(description),
    }


def _timings_record(timings) -> dict:
    return {"backend": timings.backend, "first_frame_s": timings.first_frame_s, "fps": timings.fps,
            "fps_frames": timings.fps_frames, "frame_seconds": list(timings.frame_seconds)}


def _scene_doc(args: argparse.Namespace, result: SceneRender, outputs: list[str]) -> dict:
    """``shrm render --json`` of one environment (data_specs/render_outputs.md)."""
    return {
        "mesh": result.mesh.name, "triangles": result.mesh.n_triangles, "mode": result.mode,
        "size": result.size, "camera": args.camera, "frames": len(result.frames),
        "model": _model_record(result.built.info, result.built.description),
        "timings": _timings_record(result.timings), "outputs": outputs,
    }


def _sequence_doc(args: argparse.Namespace, seq: SequenceRender, outputs: list[str]) -> dict:
    """``shrm render --json`` of an environment sequence (data_specs/render_outputs.md)."""
    first = seq.renders[0]
    orders = None if seq.orders is None else {"F": seq.orders.F, "P": seq.orders.P, "seconds": seq.orders_seconds}
    return {
        "mesh": first.mesh.name, "triangles": first.mesh.n_triangles, "mode": first.mode, "size": first.size,
        "camera": args.camera, "orders": orders,
        "sequence": [{"environment": name, "model": _model_record(r.built.info, r.built.description),
                      "timings": _timings_record(r.timings), "frame_seconds": seconds}
                     for r, name, seconds in zip(seq.renders, seq.environments, seq.frame_seconds, strict=True)],
        "outputs": outputs,
    }


def _analysed_brdf(args: argparse.Namespace) -> tuple[Any, dict | None]:
    """The BRDF rendered — the file's, or for scattered measurements the representation chosen by
    held-out error (``cli.common.load_analysis_brdf``), whose line is said — and that choice's
    record for ``--json`` (``representation``; None for an evaluable BRDF)."""
    _, brdf, choice = load_analysis_brdf(args.brdf, args, quiet=args.json)
    if choice is not None and not args.json:
        say(choice.line())
    return brdf, None if choice is None else choice.as_dict()


def _resolve_exposure(args: argparse.Namespace, env: Any) -> None:
    """``--exposure`` when given, else the stops that bring ``env``'s mean luminance to middle grey
    (``render.preview.preview_exposure``, the rule of ``shrm view``), said on one line: a first
    render of a dim map (Grace's mean is 0.016) is then not nearly black."""
    if args.exposure is None:
        args.exposure = preview_exposure(env)
        if not args.json:
            say(f"exposure {args.exposure:+.2f} stops (the environment's mean brought to middle grey; "
                "--exposure sets it)")


def run(args: argparse.Namespace) -> int:
    sources, sequence = env_sources_arg(args.env)
    cameras, options = _validate(args, sequence)
    for path in (args.output, args.exr, args.error_image):
        if path:
            check_writable(path)
    mesh = load_mesh(args.mesh)
    if sequence:
        maps = load_env_sequence(sources, args)  # every member read first: a bad one stops before any output
        _resolve_exposure(args, maps[0])  # one exposure for every frame (the first map's): no flicker
        brdf, representation = _analysed_brdf(args)
        seq = render_sequence(mesh, maps, brdf, mode=args.mode, eps=args.eps,
                              camera=cameras[0], size=args.size, background=args.background,
                              fps_frames=0, options=options)
        if not args.json:
            _report_sequence(args, seq)
        outputs = _write(args, seq.frames, len(seq.frames))
        if args.json:
            print_json({**_sequence_doc(args, seq, outputs), "exposure": args.exposure,
                        "representation": representation})
        return 0
    env = load_env_arg(sources[0], args)
    _resolve_exposure(args, env)
    brdf, representation = _analysed_brdf(args)
    result = render_scene(
        mesh, env, brdf, mode=args.mode, eps=args.eps, camera=cameras, size=args.size,
        background=args.background, fps_frames=args.fps_frames, options=options,
    )
    if not args.json:
        _report(args, result)
    errors = error_image(result) if args.error_image else None  # computed before any file is written
    outputs = _write(args, result.frames)
    if errors is not None:
        line = write_error_image_line(args.error_image, errors)
        outputs.append(str(args.error_image))
        if not args.json:
            say(line)
    if args.json:
        doc = _scene_doc(args, result, outputs)
        doc["environment"] = env.name
        doc["exposure"] = args.exposure
        doc["representation"] = representation
        if errors is not None:
            doc["error_image"] = errors.summary()
        print_json(doc)
    return 0
