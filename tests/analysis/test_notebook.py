"""Notebook cards of the order choice and the SHRM: the numbers shown are the objects' own, the
picture is a PNG an independent reader (Pillow) decodes, and it is the distant-viewer map of RH02
eq. 12 (``SHRM.view_map``) at the zenith."""

from __future__ import annotations

import base64
import io
import re

import numpy as np
import pytest
from PIL import Image

import shrmkit
from shrmkit.analysis.notebook import THUMBNAIL_VIEW, stated_band


@pytest.fixture(scope="module")
def shrm() -> shrmkit.SHRM:
    return shrmkit.prefilter("builtin:sky,height=32", "phong:s=30", eps=0.03)


def test_order_choice_card() -> None:
    choice = shrmkit.choose_orders("phong:s=30", eps=0.03)
    html = choice._repr_html_()
    assert f"{choice.F}, {choice.P}" in html and "converged" in html
    assert html.count("<tr>") >= len(choice.view_bands()) + 1  # a row per band under the header


def test_shrm_card_states_the_worst_band(shrm: shrmkit.SHRM) -> None:
    html = shrm._repr_html_()
    worst = stated_band(shrm.meta)
    expected = max(b["predicted_rel_rms"] for b in shrm.meta["view_bands"] if b["inside"])
    assert worst["predicted_rel_rms"] == expected
    assert f"relative RMS {expected:.3g}" in html
    assert f"{shrm.height} × {shrm.width}" in html and "total" in html  # the timings
    (data,) = re.findall(r'src="data:image/png;base64,([A-Za-z0-9+/=]+)"', html)
    assert base64.b64decode(data) == shrm._repr_png_()


def test_shrm_picture_is_the_zenith_view_map(shrm: shrmkit.SHRM) -> None:
    """Reference: SHRM.view_map (RH02 eq. 12) at the zenith; on a 32-row SHRM the thumbnail takes
    every pixel, so its brightest pixel is the view map's."""
    picture = np.asarray(Image.open(io.BytesIO(shrm._repr_png_())))
    assert picture.shape == (shrm.height, shrm.width, 3)
    view = shrm.view_map(np.asarray(THUMBNAIL_VIEW))
    luma = view @ np.array([0.2126, 0.7152, 0.0722])
    i, j = np.unravel_index(np.argmax(luma), luma.shape)
    assert picture[i, j].sum() == picture.sum(axis=2).max()
