"""``shrm export``: material snippets, MERL tables, DDS and KTX2 cube mip chains, bad input (exit 2, nothing written).

References: the MERL file read back by an independent transcription of MERL's ``BRDFRead.cpp``
(its half/difference construction by ``rotate_vector``, floor lookup and channel scales) and
compared with the analytic BRDF evaluated directly; the DDS header parsed by the layout of
Microsoft's DDS programming guide; the KTX2 level index parsed by the KTX 2.0 spec's layout
and its texels compared with the DDS file's; the snippet re-parsed as XML.
"""

from __future__ import annotations

import json
import re
import struct
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from shrmkit.brdf_io.specs import brdf_from_spec
from shrmkit.cli.main import main

CT = "cook-torrance:kd=0.1/0.2/0.3,ks=0.5,alpha=0.3,f0=0.9/0.6/0.3,dist=ggx"


def test_material_snippet_and_json(tmp_path, capsys):
    out = tmp_path / "paint.xml"
    assert main(["export", CT, "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "not exact: Mitsuba 3 has no Schlick Fresnel" in text and "measured error against" in text
    root = ET.fromstring(out.read_text())
    assert root.find("bsdf").get("id") == "paint" and root.find("bsdf").get("type") == "blendbsdf"
    assert main(["export", "lambert:albedo=0.5", "-o", str(tmp_path / "l.pbrt"), "--name", "grey", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["format"] == "pbrt" and doc["exact"] and doc["name"] == "grey" and doc["rel_rms"] == 0
    assert 'MakeNamedMaterial "grey" "string type" "diffuse" "rgb reflectance" [ 0.5 0.5 0.5 ]' in (
        tmp_path / "l.pbrt").read_text()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["l.pbrt", "paint.xml"]


def _rotate(v: np.ndarray, axis: np.ndarray, angle: float) -> np.ndarray:
    """BRDFRead.cpp rotate_vector."""
    c, s = np.cos(angle), np.sin(angle)
    return v * c + axis * np.dot(axis, v) * (1 - c) + np.cross(axis, v) * s


def _brdfread_lookup(table: np.ndarray, L: np.ndarray, V: np.ndarray) -> np.ndarray:
    """BRDFRead.cpp lookup_brdf_val: half/diff angles, floor indices, channel scales."""
    half = (L + V) / np.linalg.norm(L + V)
    theta_h, phi_h = np.arccos(half[2]), np.arctan2(half[1], half[0])
    diff = _rotate(_rotate(L, np.array([0.0, 0, 1]), -phi_h), np.array([0.0, 1, 0]), -theta_h)
    theta_d, phi_d = np.arccos(diff[2]), np.arctan2(diff[1], diff[0])
    i = 0 if theta_h <= 0 else min(max(int(np.sqrt(theta_h / (np.pi / 2)) * 90), 0), 89)
    j = min(max(int(theta_d / (np.pi / 2) * 90), 0), 89)
    k = min(max(int((phi_d + np.pi if phi_d < 0 else phi_d) / np.pi * 180), 0), 179)
    index = k + j * 180 + i * 180 * 90
    n = 90 * 90 * 180
    return np.array([table[index], table[index + n], table[index + 2 * n]]) * np.array([1, 1.15, 1.66]) / 1500


def test_merl_read_back_by_brdfread(tmp_path, capsys):
    """Directions at the centres of random bins, looked up as BRDFRead.cpp does, give the analytic
    BRDF at the bin's sample position (its lower edge, data_specs/merl_binary.md) to rounding, and
    the BRDF at the bin centre to within the bin's variation."""
    out = tmp_path / "ct.binary"
    assert main(["export", CT, "-o", str(out), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["format"] == "merl" and doc["readback_max_rel"] < 1e-12 and doc["bytes"] == 34_992_012
    raw = out.read_bytes()
    assert struct.unpack("<3i", raw[:12]) == (90, 90, 180)
    table = np.frombuffer(raw, dtype="<f8", offset=12)
    brdf = brdf_from_spec(CT)
    rng = np.random.default_rng(7)
    checked = 0
    for i, j, k in zip(rng.integers(0, 90, 400), rng.integers(0, 90, 400), rng.integers(0, 180, 400), strict=True):
        def directions(a, b, c):
            th, td, pd = (a / 90) ** 2 * np.pi / 2, b * np.pi / 180, c * np.pi / 180
            D = np.array([np.sin(td) * np.cos(pd), np.sin(td) * np.sin(pd), np.cos(td)])
            Ry = np.array([[np.cos(th), 0, np.sin(th)], [0, 1, 0], [-np.sin(th), 0, np.cos(th)]])
            return Ry @ D, Ry @ (D * [-1, -1, 1])

        L, V = directions(i + 0.5, j + 0.5, k + 0.5)
        L0, V0 = directions(i, j, k)
        if min(L[2], V[2], L0[2], V0[2]) < 0.1:
            continue
        looked_up = _brdfread_lookup(table, L, V)
        assert np.allclose(looked_up, brdf.eval(L0, V0), rtol=1e-9)
        assert np.allclose(looked_up, brdf.eval(L, V), rtol=0.25)
        checked += 1
    assert checked > 100


def test_dds_chain_and_sidecar(tmp_path, capsys):
    out = tmp_path / "sky.dds"
    assert main(["export", CT, "--env", "builtin:sky", "-o", str(out), "--face-size", "8", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    sidecar = json.loads((tmp_path / "sky.dds.json").read_text())
    assert [lv["roughness"] for lv in sidecar["levels"]] == pytest.approx([0, 1 / 3, 2 / 3, 1])
    assert [lv["size"] for lv in sidecar["levels"]] == [8, 4, 2, 1]
    assert sidecar["brdf_alpha"] == pytest.approx(0.3) and sidecar["brdf_lod"] == pytest.approx(np.sqrt(0.3) * 3)
    assert doc["sidecar"].endswith("sky.dds.json") and doc["face_size"] == 8
    raw = out.read_bytes()
    assert raw[:4] == b"DDS " and struct.unpack_from("<I", raw, 28)[0] == 4 and raw[84:88] == b"DX10"
    assert len(raw) == 148 + 6 * (64 + 16 + 4 + 1) * 8
    # the same chain as KTX 2.0 (picked by the suffix): each level's index entry (KTX spec: byte 80,
    # 24 bytes a level, largest first) points at the DDS file's surfaces of that level, face by face
    ktx = tmp_path / "sky.ktx2"
    assert main(["export", CT, "--env", "builtin:sky", "-o", str(ktx), "--face-size", "8", "-q"]) == 0
    data = ktx.read_bytes()
    assert data[:12] == b"\xabKTX 20\xbb\r\n\x1a\n" and struct.unpack_from("<I", data, 12)[0] == 97
    at = 148
    for face in range(6):
        for level, s in enumerate((8, 4, 2, 1)):
            offset = struct.unpack_from("<Q", data, 80 + 24 * level)[0] + face * s * s * 8
            assert data[offset : offset + s * s * 8] == raw[at : at + s * s * 8]
            at += s * s * 8
    ktx_sidecar = json.loads((tmp_path / "sky.ktx2.json").read_text())
    assert {k: v for k, v in ktx_sidecar.items() if k not in ("file", "seconds")} == {
        k: v for k, v in sidecar.items() if k not in ("file", "seconds")}


@pytest.mark.parametrize(("args", "message"), [
    (["lambert:albedo=0.5", "-o", "x.png"], "suffix '.png' is not a format written"),
    (["lambert:albedo=0.5", "-o", "x.dds"], "--to dds needs --env"),
    (["lambert:albedo=0.5", "-o", "x.ktx2"], "--to ktx2 needs --env"),
    (["lambert:albedo=0.5", "-o", "x.xml", "--env", "builtin:sky"], "--env is for --to dds"),
    (["lambert:albedo=0.5", "-o", "x.dds", "--env", "builtin:sky", "--face-size", "12"], "power of two"),
    (["lambert:albedo=7", "-o", "x.xml"], "albedo=7 outside"),
    (["lambert:albedo=0.5", "-o", "x.xml", "--name", "a b"], "--name 'a b'"),
    (["lambert:albedo=0.5", "-o", "x.xml", "--to", "pbrt"], "pbrt files end in .pbrt"),
])
def test_bad_input_one_line_exit_2(tmp_path, monkeypatch, run_main, args, message):
    monkeypatch.chdir(tmp_path)
    code, err = run_main("export", *args)
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("suffix", [".ktx2", ".dds"])
def test_side_file_path_checked_before_the_work(tmp_path, monkeypatch, run_main, suffix):
    """A folder where the side file OUTPUT.json goes: refused before the work, one line naming it,
    and no container left on disk (it used to be written, then the side file failed)."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / f"s{suffix}.json").mkdir()
    code, err = run_main("export", "phong:s=32", "--env", "builtin:sky", "-o", f"s{suffix}", "--face-size", "8")
    assert code == 2 and f"s{suffix}.json: is a folder" in err and len(err.strip().splitlines()) == 1
    assert [p.name for p in tmp_path.iterdir()] == [f"s{suffix}.json"]
    assert not list((tmp_path / f"s{suffix}.json").iterdir())


@pytest.mark.parametrize(("output", "message"), [
    ("afile/x.ktx2", "afile/x.ktx2: afile is a file, not a folder"),
    ("afile/sub/x.xml", "afile/sub/x.xml: afile is a file, not a folder"),
    (".ktx2", "the file name '.ktx2' has no stem (a hidden file name, no suffix): name the file, e.g. sky.ktx2"),
])
def test_output_path_messages(tmp_path, monkeypatch, run_main, output, message):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "afile").write_text("x")
    code, err = run_main("export", "phong:s=32", "--env", "builtin:sky", "-o", output, "--face-size", "8") \
        if output.endswith(".ktx2") else run_main("export", "lambert:albedo=0.5", "-o", output)
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile"]


def test_missing_output_folder_is_created_as_every_verb_does(tmp_path, capsys):
    out = tmp_path / "new" / "deeper" / "sky.ktx2"
    assert main(["export", "lambert:albedo=0.5", "--env", "builtin:sky,height=64", "-o", str(out), "--face-size", "2",
                 "-q"]) == 0
    assert out.is_file() and (out.parent / "sky.ktx2.json").is_file()


def test_black_map_refused(tmp_path, monkeypatch, run_main):
    """An all-zero map is refused as shrm prefilter refuses it ("black"), nothing written."""
    from shrmkit.brdf_io.rgbe import write_hdr

    write_hdr(tmp_path / "black.hdr", np.zeros((8, 16, 3), np.float32))
    monkeypatch.chdir(tmp_path)
    code, err = run_main("export", "lambert:albedo=0.5", "--env", "black.hdr", "-o", "b.ktx2", "--face-size", "4")
    assert code == 2 and "black" in err and len(err.strip().splitlines()) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["black.hdr"]


def test_one_level_chain_says_it_cannot_hold_the_roughness(tmp_path, capsys):
    """--levels 1 holds roughness 0 only: the material's roughness √0.3 cannot be represented; the
    line and the side file say so (the rule m/(N − 1) is 0/0 there)."""
    out = tmp_path / "one.ktx2"
    assert main(["export", CT, "--env", "builtin:sky", "-o", str(out), "--face-size", "1", "--levels", "1"]) == 0
    text = capsys.readouterr().out
    assert "note: a one-level chain holds roughness 0 only: it cannot represent the material's roughness 0.548" in text
    assert "reads level" not in text
    side = json.loads((tmp_path / "one.ktx2.json").read_text())
    assert side["brdf_lod"] == 0.0 and [lv["roughness"] for lv in side["levels"]] == [0.0]
    assert "cannot represent the material's roughness 0.548 (GGX alpha 0.3)" in side["brdf_note"]
    assert side["roughness_rule"].startswith("one level: roughness 0")


def test_snippet_comments_state_what_the_json_states(tmp_path, capsys):
    """phong:s=100 is exported as its closest Cook-Torrance fit: the JSON says exact false, and so do
    the XML comment and the mitsuba-dict file (they used to say "exact" from the fit's own mapping)."""
    out = tmp_path / "p.xml"
    assert main(["export", "phong:s=100", "-o", str(out), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["exact"] is False and doc["model_note"].startswith("no exact counterpart for PhongLobe")
    comments = re.findall(r"<!--(.*?)-->", out.read_text())
    assert not any("exact: the renderer's BSDF equals" in c for c in comments)
    assert any(c.strip() == f"not exact: {doc['model_note']}" for c in comments)
    assert main(["export", "phong:s=100", "-o", str(tmp_path / "p.json"), "-q"]) == 0
    side = json.loads((tmp_path / "p.json").read_text())
    assert side["exact"] is False and side["model_note"] == doc["model_note"]


def test_container_taken_back_when_its_side_file_fails_after_the_check(tmp_path, monkeypatch, run_main):
    """The side file fails after the early check (a folder made in between, here with the check
    skipped): the container this run moved into place is removed, nothing is left."""
    import shrmkit.cli.cmd_export as cmd_export

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(cmd_export, "_check_outputs", lambda paths: None)
    (tmp_path / "s.ktx2.json").mkdir()
    code, err = run_main("export", "lambert:albedo=0.5", "--env", "builtin:sky,height=64", "-o", "s.ktx2",
                         "--face-size", "2")
    assert code == 2 and "s.ktx2.json: cannot write" in err and len(err.strip().splitlines()) == 1
    assert [p.name for p in tmp_path.iterdir()] == ["s.ktx2.json"]
