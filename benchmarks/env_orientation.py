"""Which orientation do lat-long files in the wild have? The evidence behind ``load_env``'s y-up default.

For each real lat-long map in ``../shared/data/env`` that has an independent reference, the map is read
y-up (the default, ``up="y"``) and literally (``up="z"``), each turned to every azimuth (whole columns)
and compared with the reference; a mirrored reading matches at no azimuth. References:

- ``mitsuba``: Mitsuba 3's ``envmap`` emitter loading the same file (``scalar_rgb``; its world direction
  (x, y, z) is our (z, x, y), data_specs/environment_maps.md §3.1), evaluated toward 2000 random
  directions; score: correlation of log(1 + mean RGB);
- ``envmap attr``: OpenEXR's own reading of a file whose ``envmap`` attribute states its orientation,
  against the same pixels read as a plain lat-long map (32 rows); score: 1 − relative log-RMS;
- ``cube``: Debevec's 1999 cube map of the same scene (Direct3D faces; 32 rows); score: correlation of
  log mean RGB (10⁻⁴ added).

The table gives, per map and reading, the best azimuth and its score. Data are read from
``../shared/data`` (never copied into the repository); Mitsuba rows are skipped where it is not installed.

Run:  .venv/bin/python benchmarks/env_orientation.py      (≈ 15 s CPU)
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from shrmkit.brdf_io.envmap import EnvironmentMap, load_env
from shrmkit.brdf_io.exr import read_exr_image

__all__ = ["main", "rows"]

ENV = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "env"
ROWS = 32


def _best(scores: list[float]) -> tuple[float, float]:
    """(azimuth in degrees, score) of the best whole-column turn."""
    k = int(np.argmax(scores))
    return 360.0 * k / len(scores), float(scores[k])


def _mitsuba_rows(path: Path) -> list[tuple]:
    try:
        import mitsuba as mi
    except ImportError:
        return []
    mi.set_variant("scalar_rgb")
    emitter = mi.load_dict({"type": "envmap", "filename": str(path)})
    rng = np.random.default_rng(1)
    dirs = rng.normal(size=(2000, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    theirs = []
    for x, y, z in dirs:
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(-y, -z, -x)
        theirs.append(float(np.mean(np.array(emitter.eval(si)))))
    ref = np.log1p(np.array(theirs))
    out = []
    for up in ("y", "z"):
        env = load_env(path, up=up)
        scores = []
        for k in range(64):
            turned = env.rotated_z(2 * np.pi * k / 64)
            scores.append(float(np.corrcoef(np.log1p(turned.lookup(dirs).mean(axis=1)), ref)[0, 1]))
        out.append((path.name, "mitsuba", up, *_best(scores)))
    return out


def _attr_rows(path: Path) -> list[tuple]:
    stated = load_env(path, height=ROWS).radiance
    b = np.log1p(stated)
    data = read_exr_image(path).data.astype(np.float32)
    out = []
    for up in ("y", "z"):
        image = data if up == "z" else data[:, (data.shape[1] // 2 - 1 - np.arange(data.shape[1])) % data.shape[1]]
        plain = EnvironmentMap(np.ascontiguousarray(image), path.stem).resized(ROWS).radiance
        scores = [1.0 - float(np.sqrt(np.mean((np.log1p(np.roll(plain, k, axis=1)) - b) ** 2) / np.mean(b**2)))
                  for k in range(2 * ROWS)]
        out.append((path.name, "envmap attr", up, *_best(scores)))
    return out


def _cube_rows(path: Path, cube: str, flip: bool) -> list[tuple]:
    ref = np.log(load_env(ENV / "debevec1999_cubes" / cube, height=ROWS).radiance.mean(-1) + 1e-4).ravel()
    out = []
    for up in ("y", "z"):
        m = load_env(path, up=up, flip=flip, height=ROWS).radiance
        scores = [float(np.corrcoef(np.log(np.roll(m, k, axis=1).mean(-1) + 1e-4).ravel(), ref)[0, 1])
                  for k in range(2 * ROWS)]
        out.append((path.name + (" (flip)" if flip else ""), f"cube {cube}", up, *_best(scores)))
    return out


def rows() -> list[tuple]:
    """(map, reference, up, best azimuth in degrees, score) for every map with a reference."""
    out: list[tuple] = []
    for name in ("venice_sunset_1k.hdr", "royal_esplanade_1k.hdr"):
        out += _mitsuba_rows(ENV / "polyhaven_cc0" / name)
    for name in ("KernerEnvLatLong.exr", "OrientationLatLong.exr"):
        out += _attr_rows(ENV / "openexr_images" / name)
    out += _cube_rows(ENV / "grace_latlong.exr", "grace", True)
    out += _cube_rows(ENV / "ict_small" / "uffizi.hdr", "uffizi", False)
    return out


def main() -> int:
    if not ENV.is_dir():
        print(f"no shared data at {ENV}", file=sys.stderr)
        return 1
    print(f"{'map':28s} {'reference':14s} {'up':3s} {'best azimuth':>12s} {'score':>8s}")
    for name, ref, up, azimuth, score in rows():
        print(f"{name:28s} {ref:14s} {up:3s} {azimuth:12.1f} {score:8.4f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
