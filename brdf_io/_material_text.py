"""Snippet text of an exported material in each renderer's syntax: Mitsuba 3 XML/dict, pbrt-v4, MaterialX.

One writer per target (``_text_mitsuba``, ``_text_mitsuba_dict``, ``_text_pbrt``,
``_text_materialx``), each opening with the comment lines of :func:`_header` (what the JSON of
``shrm export`` states: exact or not, the measured error); :func:`mitsuba_dict` is the material as
a ``mitsuba.load_dict`` dict. Numbers are written with 9 significant digits (float32 round trip).
:mod:`.export_material` pairs them with the converters in ``MATERIAL_TARGETS`` and re-exports the
public names; the layouts are in ``data_specs/export.md``.

References: [Mitsuba3] scene XML; the pbrt-v4 scene file format (``MakeNamedMaterial``);
[MaterialX] (``standard_surface``, ``surfacematerial``). Citation keys: ``data_specs/bibliography.md``.
"""

from __future__ import annotations

import json
from typing import Any
from xml.sax.saxutils import quoteattr

from ._exported_material import ExportedMaterial


def _rgb(values: list[float]) -> str:
    return ", ".join(f"{v:.9g}" for v in values)


def _mitsuba_xml(node: dict[str, Any], indent: str, name: str | None = None) -> list[str]:
    head = f'{indent}<bsdf type="{node["type"]}"' + (f" id={quoteattr(name)}" if name else "") + ">"
    lines = [head]
    inner = indent + "    "
    for key, value in node.items():
        if key == "type":
            continue
        if isinstance(value, dict):
            lines += _mitsuba_xml(value, inner)
        elif isinstance(value, list):
            lines.append(f'{inner}<rgb name="{key}" value="{_rgb(value)}"/>')
        elif isinstance(value, str):
            lines.append(f'{inner}<string name="{key}" value={quoteattr(value)}/>')
        else:
            lines.append(f'{inner}<float name="{key}" value="{value:.9g}"/>')
    return lines + [f"{indent}</bsdf>"]


def mitsuba_dict(material: ExportedMaterial) -> dict[str, Any]:
    """The material as a Mitsuba 3 Python dict for ``mitsuba.load_dict`` (RGB values as
    ``{"type": "rgb", "value": [r, g, b]}``)."""
    def convert(node: dict[str, Any]) -> dict[str, Any]:
        return {key: convert(v) if isinstance(v, dict) else {"type": "rgb", "value": v} if isinstance(v, list) else v
                for key, v in node.items()}
    return convert(material.native)


def _header(material: ExportedMaterial, comment: str, error: str | None, model_note: str | None) -> list[str]:
    """The snippet's comment lines: what the JSON of ``shrm export`` states (``exact`` only when the
    renderer's BSDF is the source BRDF: no closest model, no approximate mapping)."""
    lines = [f"exported by shrmkit from {material.source}"]
    if model_note:
        lines.append(f"not exact: {model_note}")
    if not material.exact:
        lines.append(f"not exact: {material.note}")
    elif not model_note:
        lines.append("exact: the renderer's BSDF equals the model")
    if error:
        lines.append(error)
    return [f"{comment} {line}" for line in lines]


def _text_mitsuba(material: ExportedMaterial, name: str, error: str | None,
                 model_note: str | None = None) -> str:
    comments = "\n".join(f"    <!-- {c[2:].replace('--', '-')} -->" for c in _header(material, "# ", error, model_note))
    return "\n".join(['<?xml version="1.0" encoding="utf-8"?>', '<scene version="3.0.0">', comments,
                      *_mitsuba_xml(material.native, "    ", name), "</scene>", ""])


def _text_mitsuba_dict(material: ExportedMaterial, name: str, error: str | None,
                      model_note: str | None = None) -> str:
    doc = {"format": "shrmkit-mitsuba-dict", "name": name, "source": material.source,
           "exact": material.exact and not model_note, "model_note": model_note or None,
           "note": material.note, "error": error, "bsdf": mitsuba_dict(material)}
    return json.dumps(doc, indent=2) + "\n"


def _pbrt_params(node: dict[str, Any]) -> str:
    parts = []
    for key, value in node.items():
        if key in ("type", "materials"):
            continue
        if isinstance(value, bool):
            parts.append(f'"bool {key}" {str(value).lower()}')
        elif isinstance(value, int):
            parts.append(f'"integer {key}" {value}')
        elif isinstance(value, list):
            parts.append(f'"rgb {key}" [ {" ".join(f"{v:.9g}" for v in value)} ]')
        else:
            parts.append(f'"float {key}" {value:.9g}')
    return " ".join(parts)


def _text_pbrt(material: ExportedMaterial, name: str, error: str | None,
              model_note: str | None = None) -> str:
    lines = _header(material, "#", error, model_note)
    node = material.native
    if node["type"] == "mix":
        names = [f"{name}-diffuse", f"{name}-conductor"]
        for part, part_name in zip(node["materials"], names, strict=True):
            lines.append(f'MakeNamedMaterial "{part_name}" "string type" "{part["type"]}" {_pbrt_params(part)}')
        lines.append(f'MakeNamedMaterial "{name}" "string type" "mix" "string materials" [ "{names[0]}" '
                     f'"{names[1]}" ] {_pbrt_params(node)}')
    else:
        lines.append(f'MakeNamedMaterial "{name}" "string type" "{node["type"]}" {_pbrt_params(node)}')
    lines.append(f'# use it with: NamedMaterial "{name}"')
    return "\n".join(lines) + "\n"


def _text_materialx(material: ExportedMaterial, name: str, error: str | None,
                   model_note: str | None = None) -> str:
    lines = ['<?xml version="1.0"?>', '<materialx version="1.38">']
    lines += [f"  <!-- {c[2:].replace('--', '-')} -->" for c in _header(material, "# ", error, model_note)]
    shader = f"SR_{name}"
    lines.append(f'  <standard_surface name={quoteattr(shader)} type="surfaceshader">')
    for key, value in material.native.items():
        if isinstance(value, list):
            lines.append(f'    <input name="{key}" type="color3" value="{_rgb(value)}" />')
        else:
            lines.append(f'    <input name="{key}" type="float" value="{value:.9g}" />')
    lines += ["  </standard_surface>",
              f'  <surfacematerial name={quoteattr(name)} type="material">',
              f'    <input name="surfaceshader" type="surfaceshader" nodename={quoteattr(shader)} />',
              "  </surfacematerial>", "</materialx>", ""]
    return "\n".join(lines)
