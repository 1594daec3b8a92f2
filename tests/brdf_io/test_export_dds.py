"""DDS cube mip chains (brdf_io/dds.py) and the GGX-prefiltered cube chain (analysis/prefiltered_cube.py).

References: Microsoft's DDS layout (``DDS_HEADER``, ``DDS_PIXELFORMAT``, ``DDS_HEADER_DXT10``,
"Programming Guide for DDS") parsed here independently with ``struct``; Pillow's DDS reader
(``PIL.DdsImagePlugin``, Pillow 13, reads the first surface of an R8G8B8A8 DX10 file); Karis's
prefilter summed directly over every pixel of the map (the slow direct path); a constant map,
which every level must reproduce exactly.
"""

from __future__ import annotations

import struct

import numpy as np
import pytest

from shrmkit.analysis.prefiltered_cube import chain_roughness, ggx_cube_chain, material_lod
from shrmkit.brdf_io.dds import read_dds_cube, write_dds_cube
from shrmkit.brdf_io.errors import BadInputError


def _chain(size: int, seed: int = 0) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    return [rng.uniform(0, 4, (6, max(1, size >> m), max(1, size >> m), 3)) for m in range(size.bit_length())]


def _parse_dds(data: bytes) -> dict:
    """An independent reader of the DDS header (Microsoft Docs field order, little-endian)."""
    assert data[:4] == b"DDS "
    (size, flags, height, width, pitch, depth, mips) = struct.unpack_from("<7I", data, 4)
    pf_size, pf_flags, fourcc = struct.unpack_from("<II4s", data, 4 + 72)
    caps, caps2 = struct.unpack_from("<II", data, 4 + 104)
    dxgi, dim, misc, array_size, misc2 = struct.unpack_from("<5I", data, 128)
    return dict(size=size, flags=flags, height=height, width=width, pitch=pitch, mips=mips, pf_size=pf_size,
                pf_flags=pf_flags, fourcc=fourcc, caps=caps, caps2=caps2, dxgi=dxgi, dim=dim, misc=misc,
                array_size=array_size, data_offset=148)


@pytest.mark.parametrize(("fmt", "dxgi", "dtype"), [("rgba32f", 2, "<f4"), ("rgba16f", 10, "<f2")])
def test_dds_layout_by_the_spec(tmp_path, fmt, dxgi, dtype):
    """Header fields and the face-major surface order (each face followed by its mips)."""
    chain = _chain(8)
    path = write_dds_cube(tmp_path / "c.dds", chain, fmt=fmt)
    data = path.read_bytes()
    h = _parse_dds(data)
    assert (h["size"], h["pf_size"], h["width"], h["height"], h["mips"]) == (124, 32, 8, 8, 4)
    assert h["flags"] & 0x1 and h["flags"] & 0x1000 and h["flags"] & 0x20000  # CAPS, PIXELFORMAT, MIPMAPCOUNT
    assert h["pf_flags"] & 0x4 and h["fourcc"] == b"DX10"
    assert h["caps"] & 0x8 and h["caps"] & 0x1000 and h["caps"] & 0x400000  # COMPLEX, TEXTURE, MIPMAP
    assert h["caps2"] == 0x200 | 0xFC00  # CUBEMAP and all six faces
    assert (h["dxgi"], h["dim"], h["misc"], h["array_size"]) == (dxgi, 3, 0x4, 1)
    texels = np.frombuffer(data, dtype=dtype, offset=h["data_offset"]).astype(np.float64)
    assert texels.size == 6 * (64 + 16 + 4 + 1) * 4
    at = 0
    tol = 0 if fmt == "rgba32f" else 2e-3
    for face in range(6):
        for level in chain:
            s = level.shape[1]
            block = texels[at : at + s * s * 4].reshape(s, s, 4)
            assert np.allclose(block[..., :3], level[face], rtol=tol, atol=1e-6)
            assert np.all(block[..., 3] == 1.0)
            at += s * s * 4
    back, name = read_dds_cube(path)
    assert name == fmt and [b.shape for b in back] == [c.shape for c in chain]


def test_pillow_reads_the_first_surface(tmp_path):
    """Pillow's DDS reader (an outside parser) sees a 16 x 16 RGBA image equal to face +X, level 0."""
    image = pytest.importorskip("PIL.Image")
    chain = [np.clip(level / 4, 0, 1) for level in _chain(16, seed=3)]
    path = write_dds_cube(tmp_path / "c8.dds", chain, fmt="rgba8")
    with image.open(path) as im:
        assert im.format == "DDS" and im.size == (16, 16) and im.mode == "RGBA"
        pixels = np.asarray(im)
    assert np.array_equal(pixels[..., :3], np.rint(chain[0][0] * 255).astype(np.uint8))
    assert np.all(pixels[..., 3] == 255)


def test_dds_refusals(tmp_path):
    chain = _chain(4)
    with pytest.raises(BadInputError, match="mip level 1 has shape"):
        write_dds_cube(tmp_path / "a.dds", [chain[0], chain[0]])
    with pytest.raises(BadInputError, match="float16"):
        write_dds_cube(tmp_path / "a.dds", [np.full((6, 1, 1, 3), 1e5)])
    with pytest.raises(BadInputError, match="NaN"):
        write_dds_cube(tmp_path / "a.dds", [np.full((6, 1, 1, 3), np.nan)])
    assert not list(tmp_path.iterdir())
    path = write_dds_cube(tmp_path / "b.dds", chain)
    path.write_bytes(path.read_bytes()[:-8])
    with pytest.raises(BadInputError, match="the header implies"):
        read_dds_cube(path)


def _pixel_grid(height: int) -> tuple[np.ndarray, np.ndarray]:
    """Pixel-centre directions (H, 2H, 3) and solid angles (H,) of a lat-long map, DESIGN §2."""
    theta = (np.arange(height) + 0.5) * np.pi / height
    phi = (np.arange(2 * height) + 0.5) * np.pi / height
    d = np.stack([np.sin(theta)[:, None] * np.cos(phi), np.sin(theta)[:, None] * np.sin(phi),
                  np.broadcast_to(np.cos(theta)[:, None], (height, 2 * height))], axis=-1)
    edges = np.cos(np.arange(height + 1) * np.pi / height)
    return d, (np.pi / height) * (edges[:-1] - edges[1:])


def test_chain_against_direct_prefilter_sums():
    """Every texel of face +Y (the zenith face, project direction (v, −u, 1) for face coordinates
    (u, v)) at the α = 0.25 level equals Karis's prefilter summed over every pixel, within 2 %; a
    constant map gives a constant chain; level m holds roughness m/(N − 1)."""
    height = 32
    d, omega = _pixel_grid(height)
    radiance = np.stack([1 + np.maximum(d[..., 2], 0) * 3, 1 + np.maximum(d[..., 0], 0) ** 4 * 8,
                         np.full(d.shape[:2], 0.5)], axis=-1)
    chain = ggx_cube_chain(radiance, face_size=16)
    assert chain.roughness == tuple(chain_roughness(5)) == (0.0, 0.25, 0.5, 0.75, 1.0)
    assert [level.shape for level in chain.levels] == [(6, s, s, 3) for s in (16, 8, 4, 2, 1)]
    alpha = 0.25
    level = chain.levels[2]
    c = 2 * (np.arange(4) + 0.5) / 4 - 1
    u, v = np.meshgrid(c, c)  # columns, rows
    R = np.stack([v, -u, np.ones_like(u)], axis=-1)
    R /= np.linalg.norm(R, axis=-1, keepdims=True)
    cos_g = np.einsum("rcx,hwx->rchw", R, d)
    c2 = (1 + cos_g) / 2
    k = alpha**2 / (np.pi * (c2 * (alpha**2 - 1) + 1) ** 2) * np.maximum(cos_g, 0) * omega[:, None]
    direct = np.einsum("rchw,hwk->rck", k, radiance) / k.sum(axis=(2, 3))[..., None]
    assert np.allclose(level[2], direct, rtol=0.02)
    flat = ggx_cube_chain(np.full((16, 32, 3), 0.7), face_size=4)
    assert all(np.allclose(lv, 0.7, rtol=1e-5) for lv in flat.levels)
    assert material_lod(0.25, 5) == pytest.approx(2.0)
    with pytest.raises(BadInputError, match="power of two"):
        ggx_cube_chain(radiance, face_size=12)


def test_docstring_example_runs():
    """The Examples section of write_dds_cube (a round trip in a temporary folder) passes as a doctest."""
    import doctest

    from shrmkit.brdf_io import dds

    result = doctest.testmod(dds, optionflags=doctest.NORMALIZE_WHITESPACE, report=False)
    assert result.attempted >= 5 and result.failed == 0


def test_tiny_map_roughness_one_level_averages_over_the_sphere():
    """A 1 × 2 map (500 on the half-space y > 0, 0 on y < 0) at roughness 1 (GGX α = 1: D = 1/π,
    Karis's weight is max(R·ω, 0)): the cosine-weighted average over the hemisphere around R,
    closed form 500 (1 + R_y)/2 (the view factor of a tilted plane to a half-space) at every texel
    of the 4 × 4 level, not a blend of the two pixels the texel falls between (that was off by up
    to 66); the 1 × 1 level's face centres: ±Y of the cube (zenith, nadir) read 250."""
    from shrmkit.analysis.prefiltered_cube import _texel_directions

    radiance = np.zeros((1, 2, 3))
    radiance[0, 0] = 500.0  # column 0: φ in [0, π), y > 0
    for face_size in (8, 2):
        chain = ggx_cube_chain(radiance, face_size=face_size, n_levels=2)
        level = chain.levels[-1]
        assert chain.roughness[-1] == 1.0 and level.shape == (6, face_size // 2, face_size // 2, 3)
        expected = 500.0 * (1.0 + _texel_directions(face_size // 2)[..., 1]) / 2.0
        assert np.allclose(level, expected[..., None], atol=0.5)
    assert np.allclose(level[2:4, 0, 0, :], 250.0, atol=0.01)


def test_black_map_is_refused():
    """An all-zero map is refused as shrm prefilter refuses it (no black chain)."""
    with pytest.raises(BadInputError, match="black"):
        ggx_cube_chain(np.zeros((8, 16, 3)), face_size=4)


def test_cube_frame_against_threejs_and_the_engines_formulas(tmp_path):
    """The exported cube's frame (data_specs/export.md, cube frame per engine): a y-up panorama
    written with three.js' ``equirectUv`` (u = atan2(d_z, d_x)/2π + ½, v = asin(d_y)/π + ½, v = 1
    at the top row) holding f(d) = 2 + d·a, loaded with the defaults and exported: the texel at the
    OpenGL/Vulkan/KTX cube-table direction c (written out here, faces +X … −Z) holds f(c_z, c_y, c_x),
    the mapping of Filament's ``equirectangularToCubemap`` (u = atan2(c_x, c_z)/2π + ½) — not
    f(c), glTF-IBL-Sampler's ``panoramaToCubeMap`` (u = atan2(c_z, c_x)/2π + ½), a mirror image."""
    from shrmkit.brdf_io.envmap import load_env
    from shrmkit.brdf_io.rgbe import write_hdr

    h, w = 32, 64
    v_top = (np.arange(h) + 0.5) / h
    psi = 2 * np.pi * ((np.arange(w) + 0.5) / w - 0.5)
    sin_el = np.cos(np.pi * v_top)[:, None]
    cos_el = np.sqrt(1 - sin_el**2)
    d = np.stack([cos_el * np.cos(psi), np.broadcast_to(sin_el, (h, w)), cos_el * np.sin(psi)], axis=-1)
    a = np.array([0.9, 0.5, -0.3])
    write_hdr(tmp_path / "pano.hdr", np.repeat((2 + d @ a)[..., None], 3, axis=-1).astype(np.float32))
    level = ggx_cube_chain(load_env(tmp_path / "pano.hdr"), face_size=8, n_levels=1).levels[0][..., 0]
    s = 2 * (np.arange(8) + 0.5) / 8 - 1
    sc, tc = np.meshgrid(s, s)  # columns, rows (rows top to bottom)
    one = np.ones_like(sc)
    table = [(one, -tc, -sc), (-one, -tc, sc), (sc, one, tc), (sc, -one, -tc), (sc, -tc, one), (-sc, -tc, -one)]
    c = np.stack([np.stack(face, axis=-1) for face in table])
    c /= np.linalg.norm(c, axis=-1, keepdims=True)
    ours = 2 + c[..., [2, 1, 0]] @ a
    assert np.abs(level - ours).max() < 0.02
    assert np.abs(level - (2 + c @ a)).max() > 0.5
