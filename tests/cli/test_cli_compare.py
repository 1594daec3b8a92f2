"""``shrm compare``: JSON table, strip PNG layout, Markdown section, bad input (exit 2, no output)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from PIL import Image

from shrmkit.analysis.tolerance import DEFAULT_EPS
from shrmkit.cli.main import main

FAST = ["--env", "builtin:studio,height=16", "--env-height", "16", "--pairs", "100", "--lobes", "1",
        "--elevations", "3", "--rsibr-reference-height", "0"]


def test_compare_json_strip_and_markdown(tmp_path: Path, capsys) -> None:
    strip, md = tmp_path / "strip.png", tmp_path / "table.md"
    rc = main(["compare", "microfacet:sigma=0.3", *FAST, "--json", "--strip", str(strip), "--strip-size", "32",
               "--markdown", str(md)])
    assert rc == 0
    doc = json.loads(capsys.readouterr().out)
    labels = [r["label"] for r in doc["rows"]]
    assert [r["key"] for r in doc["rows"]] == ["shrm", "shrm_low_p", "kautz_mccool", "rsibr", "gaussian_lobes_k1"]
    image = np.asarray(Image.open(strip))
    assert image.shape == (2 * 32, (1 + len(labels)) * 32, 3)
    assert image[:32, :32].max() > 0  # the reference panel is not black
    assert md.read_text().startswith("Comparison for microfacet:sigma=0.3")
    assert [p["label"] for p in doc["strip"]["panels"]] == labels
    assert list(doc)[-2:] == ["strip", "markdown"]  # the layout of data_specs/compare_json.md
    assert doc["eps"] == DEFAULT_EPS


def test_compare_table_output(capsys) -> None:
    rc = main(["compare", "phong:s=8", *FAST])
    out = capsys.readouterr().out
    assert rc == 0 and "SHRM" in out and "phong:s=8" in out
    # one table row per representation (Phong needs P = 0: no lower-P row) -> 4 rows
    assert sum(line.startswith("│") for line in out.splitlines()) >= 4


def test_compare_bad_input_exit_2(tmp_path: Path, capsys) -> None:
    strip = tmp_path / "strip.jpg"
    assert main(["compare", "phong:s=8", *FAST, "--strip", str(strip)]) == 2
    assert not strip.exists()
    assert main(["compare", "phong:s=8", *FAST[:-6], "--lobes", "9"]) == 2
    assert main(["compare", "nonsense:q=1", *FAST]) == 2
    err = capsys.readouterr().err
    assert "strip" in err and "lobes" in err


def test_compare_lower_p_not_below_p_is_explained(capsys) -> None:
    """--lower-p at or above the chosen P gives no lower-order row; stderr says why (one line)
    and which values would give one; the JSON stays as documented."""
    rc = main(["compare", "microfacet:sigma=0.3", *FAST[:-6], "--lobes", "none", "--elevations", "3",
               "--rsibr-reference-height", "0", "--lower-p", "64", "--json"])
    captured = capsys.readouterr()
    doc = json.loads(captured.out)
    keys = [r["key"] for r in doc["rows"]]
    P = doc["rows"][0]["params"]["P"]
    assert rc == 0 and "shrm_low_p" not in keys and P > 0
    assert captured.err == (f"shrm compare: note: no lower-order SHRM row: --lower-p 64 is not below the SHRM's "
                            f"P = {P} (chosen for eps {DEFAULT_EPS:g}); use --lower-p {P - 1} or less\n")
    # a valid lower P gives the row, and no note
    rc = main(["compare", "microfacet:sigma=0.3", *FAST[:-6], "--lobes", "none", "--elevations", "3",
               "--rsibr-reference-height", "0", "--lower-p", str(P - 1), "--json"])
    captured = capsys.readouterr()
    rows = {r["key"]: r for r in json.loads(captured.out)["rows"]}
    assert rows["shrm_low_p"]["params"]["P"] == P - 1 and captured.err == ""
