"""Spectral reflectance-like quantities (a BRDF per wavelength) to linear sRGB; the Rec. 709 luminance
weights (:data:`REC709_LUMA`).

Pipeline, for samples s(λ) at λ = 400, 410, ..., 700 nm:

1. CIE 1931 XYZ under the CIE D65 illuminant S(λ), normalized so that a flat spectrum
   s ≡ 1 has Y = 1 ([CIE1931] §7.1, eq. 7.1–7.3 with k = 1 / Σ S ȳ Δλ):
   X = Σ s S x̄ / Σ S ȳ, Y = Σ s S ȳ / Σ S ȳ, Z = Σ s S z̄ / Σ S ȳ.
2. Linear sRGB with the [sRGB] XYZ → RGB matrix (D65 white, no transfer curve).
3. A diagonal white balance diag(1/w), w = the sRGB of the flat spectrum s ≡ 1 from
   steps 1–2, so a spectrally flat rho = c maps to exactly (c, c, c).

Why: rho is a reflectance-like quantity, and renderers treat RGB (1, 1, 1) light as
the sRGB white, which *is* D65, so weighting by D65 is the physically consistent choice
(a grey surface lit by sRGB white stays grey). With the full 1-nm tables step 3 would be
the identity; with 10-nm sampling truncated to 400–700 nm and the 4-digit IEC matrix, w
differs from (1, 1, 1) by less than 1 % (``white_balance()`` reports it) and the
diagonal makes the flat-spectrum property exact.

References: [CIE1931] Table T.1 (D65 relative SPD) and Table T.4 (CIE 1931 2° standard
observer x̄, ȳ, z̄), here their 10-nm rows 400–700 nm; [sRGB] §5.2 (the XYZ → RGB matrix).
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "WAVELENGTHS_NM",
    "CIE1931_CMF",
    "D65_SPD",
    "XYZ_TO_LINEAR_SRGB",
    "REC709_LUMA",
    "spectral_to_xyz",
    "xyz_to_linear_srgb",
    "spectral_to_linear_srgb",
    "white_balance",
]

WAVELENGTHS_NM = np.arange(400.0, 701.0, 10.0)

# CIE 1931 2° standard observer (CIE 015:2004 Table T.4), rows λ = 400, 410, ..., 700 nm:
# columns x̄, ȳ, z̄. Over the full 380–780 nm 5-nm table each column sums to 21.3715
# (equal-energy white has x = y = 1/3); here they are the 10-nm subset.
CIE1931_CMF = np.array(
    [
        [0.014310, 0.000396, 0.067850],  # 400
        [0.043510, 0.001210, 0.207400],  # 410
        [0.134380, 0.004000, 0.645600],  # 420
        [0.283900, 0.011600, 1.385600],  # 430
        [0.348280, 0.023000, 1.747060],  # 440
        [0.336200, 0.038000, 1.772110],  # 450
        [0.290800, 0.060000, 1.669200],  # 460
        [0.195360, 0.090980, 1.287640],  # 470
        [0.095640, 0.139020, 0.812950],  # 480
        [0.032010, 0.208020, 0.465180],  # 490
        [0.004900, 0.323000, 0.272000],  # 500
        [0.009300, 0.503000, 0.158200],  # 510
        [0.063270, 0.710000, 0.078250],  # 520
        [0.165500, 0.862000, 0.042160],  # 530
        [0.290400, 0.954000, 0.020300],  # 540
        [0.433450, 0.994950, 0.008750],  # 550
        [0.594500, 0.995000, 0.003900],  # 560
        [0.762100, 0.952000, 0.002100],  # 570
        [0.916300, 0.870000, 0.001650],  # 580
        [1.026300, 0.757000, 0.001100],  # 590
        [1.062200, 0.631000, 0.000800],  # 600
        [1.002600, 0.503000, 0.000340],  # 610
        [0.854450, 0.381000, 0.000190],  # 620
        [0.642400, 0.265000, 0.000050],  # 630
        [0.447900, 0.175000, 0.000020],  # 640
        [0.283500, 0.107000, 0.000000],  # 650
        [0.164900, 0.061000, 0.000000],  # 660
        [0.087400, 0.032000, 0.000000],  # 670
        [0.046770, 0.017000, 0.000000],  # 680
        [0.022700, 0.008210, 0.000000],  # 690
        [0.011359, 0.004102, 0.000000],  # 700
    ]
)

# CIE standard illuminant D65, relative SPD (CIE 015:2004 Table T.1), λ = 400..700 nm step 10
D65_SPD = np.array(
    [
        82.7549, 91.4860, 93.4318, 86.6823, 104.865, 117.008, 117.812, 114.861, 115.923, 108.811,
        109.354, 107.802, 104.790, 107.689, 104.405, 104.046, 100.000, 96.3342, 95.7880, 88.6856,
        90.0062, 89.5991, 87.6987, 83.2886, 83.6992, 80.0268, 80.2146, 82.2778, 78.2842, 69.7213,
        71.6091,
    ]
)

# IEC 61966-2-1 §5.2: [R, G, B]_linear = M [X, Y, Z] (D65 white, Y_white = 1)
XYZ_TO_LINEAR_SRGB = np.array(
    [
        [3.2406, -1.5372, -0.4986],
        [-0.9689, 1.8758, 0.0415],
        [0.0557, -0.2040, 1.0570],
    ]
)

# ITU-R BT.709-6 item 3.2: luminance Y = 0.2126 R + 0.7152 G + 0.0722 B of linear Rec. 709 / sRGB
# (the standard's rounded weights; ``exr.luminance_weights()`` derives them from the primaries)
REC709_LUMA = np.array([0.2126, 0.7152, 0.0722])
REC709_LUMA.setflags(write=False)


def _check_wavelengths(wavelengths: np.ndarray | None) -> None:
    if wavelengths is None:
        return
    w = np.asarray(wavelengths, dtype=np.float64)
    if w.shape != WAVELENGTHS_NM.shape or not np.allclose(w, WAVELENGTHS_NM, atol=1e-6):
        raise ValueError(f"spectra must be sampled at 400, 410, ..., 700 nm (31 values), got {w.tolist()}")


def spectral_to_xyz(spectral: np.ndarray, wavelengths: np.ndarray | None = None) -> np.ndarray:
    """CIE 1931 XYZ of spectra (..., 31) under D65, normalized so s ≡ 1 gives Y = 1.

    CIE 015:2004 eq. 7.1–7.3 as sums over the 10-nm samples, k = 1 / Σ S(λ) ȳ(λ).
    """
    _check_wavelengths(wavelengths)
    s = np.asarray(spectral, dtype=np.float64)
    if s.shape[-1:] != WAVELENGTHS_NM.shape:
        raise ValueError(f"spectra need a last axis of 31 samples, got shape {s.shape}")
    weighted = D65_SPD[:, None] * CIE1931_CMF  # (31, 3)
    return s @ weighted / weighted[:, 1].sum()


def xyz_to_linear_srgb(xyz: np.ndarray) -> np.ndarray:
    """Linear sRGB (IEC 61966-2-1 matrix, D65 white) of XYZ (..., 3); no clipping."""
    return np.asarray(xyz, dtype=np.float64) @ XYZ_TO_LINEAR_SRGB.T


def white_balance() -> np.ndarray:
    """w = linear sRGB of the flat spectrum s ≡ 1 before white balancing (close to 1)."""
    return xyz_to_linear_srgb(spectral_to_xyz(np.ones(WAVELENGTHS_NM.size)))


def spectral_to_linear_srgb(spectral: np.ndarray, wavelengths: np.ndarray | None = None) -> np.ndarray:
    """White-balanced linear sRGB of spectra (..., 31): flat rho = c gives (c, c, c).

    See the module docstring for the pipeline (D65 weighting, IEC matrix, diag(1/w)).
    Negative RGB components (out-of-gamut saturated spectra) are kept, not clipped.
    """
    return xyz_to_linear_srgb(spectral_to_xyz(spectral, wavelengths)) / white_balance()
