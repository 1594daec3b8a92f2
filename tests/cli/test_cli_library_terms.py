"""Library messages name the API's parameters; the command line says them with its options
(issue 27 point 7: ``cli.common.in_cli_terms``, applied to every error ``shrm`` prints and to
``render.error_image``'s request check by ``cmd_render``).

Each case: the library's words (``layer=NAME``, ``part=NAME|INDEX``, ``name=FORMAT``, ``mode=``,
no ``--option``) and what a CLI user reads for the same input (``--env-layer NAME``, ``--env-part
NAME|INDEX``, ``--to FORMAT``, ``--mode``, ``--error-image``), one line, exit status 2.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import OpenEXR
import pytest

from shrmkit.brdf_io import export_formats
from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.exr import read_exr
from shrmkit.cli.main import main
from shrmkit.render.error_image import check_error_image_request


def _rgb(prefix: str, value: float) -> dict:
    return {f"{prefix}{c}": np.full((4, 8), value, np.float32) for c in "RGB"}


def _exr(path: Path, parts: list[tuple[str, dict]]) -> Path:
    """One part per (name, channels); a single part is written as a plain (single-part) file."""
    def head() -> dict:
        return {"type": OpenEXR.scanlineimage, "compression": OpenEXR.ZIP_COMPRESSION}

    content = head() if len(parts) == 1 else [OpenEXR.Part(head(), c, name) for name, c in parts]
    with (OpenEXR.File(content, parts[0][1]) if len(parts) == 1 else OpenEXR.File(content)) as exr:
        exr.write(str(path))
    return path


def _cli_error(capsys, argv: list[str]) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"shrm {argv[0]}: error:")
    return err


def test_exr_layer_and_part_messages(tmp_path, capsys):
    layers = _exr(tmp_path / "layers.exr", [("", {**_rgb("diffuse.", 1.0), **_rgb("specular.", 2.0)})])
    parts = _exr(tmp_path / "stereo.exr", [("left", _rgb("", 1.0)), ("right", _rgb("", 2.0))])
    cases = ((layers, "choose one with layer=NAME", "choose one with --env-layer NAME"),
             (parts, "choose one with part=NAME|INDEX:", "choose one with --env-part NAME|INDEX:"))
    for path, library, option in cases:
        with pytest.raises(BadInputError) as caught:
            read_exr(path)
        assert library in str(caught.value) and "--env" not in str(caught.value)
        out = tmp_path / "out.shrm.npz"
        err = _cli_error(capsys, ["prefilter", "--env", str(path), "--brdf", "phong:s=8", "-o", str(out)])
        assert option in err and library not in err and not out.exists()


def test_export_format_message(tmp_path, capsys, monkeypatch):
    # two formats writing one suffix (none do today): the file's suffix cannot pick one
    twin = export_formats.EXPORT_FORMATS["mitsuba"]
    monkeypatch.setitem(export_formats.EXPORT_FORMATS, "mitsuba-twin", twin)
    with pytest.raises(BadInputError, match=r"several formats: name one with name=FORMAT;"):
        export_formats.export_format(None, "m.xml")
    err = _cli_error(capsys, ["export", "phong:s=8", "-o", str(tmp_path / "m.xml")])
    assert "several formats: name one with --to FORMAT;" in err and "name=" not in err
    assert not (tmp_path / "m.xml").exists()


def test_error_image_request_messages():
    with pytest.raises(BadInputError, match=r"^err\.png: the error image path must name a \.exr file$"):
        check_error_image_request("err.png", "distant")
    with pytest.raises(BadInputError, match=r"^an error image needs an SHRM mode \(distant, perpixel, "
                                            r"kautz-mccool\), not mode=rsibr: the error statement is the SHRM's$"):
        check_error_image_request("err.exr", "rsibr")
    # what shrm render prints for the same requests: tests/cli/test_cli_error_image.py
