"""The command line's words for the library's: a library message names the API's parameters
(``max_F/max_P``, ``layer=NAME``, ``name=FORMAT``), ``shrm`` prints it with the options that set them
(``--max-F/--max-P``, ``--env-layer NAME``, ``--to FORMAT``; issue 27 point 7).

Numpy-free and import-free: ``cli/main.py`` applies :func:`in_cli_terms` to every error it prints;
``cli/cmd_render.py`` adds :data:`ERROR_IMAGE_TERMS` for ``render.error_image``'s request check.
"""

from __future__ import annotations

__all__ = ["OPTION_OF", "ERROR_IMAGE_TERMS", "in_cli_terms"]

#: The library's names of the parameters a message may name (the limits to raise, the OpenEXR layer
#: or part to choose, the export format to name: ``brdf_io.exr``, ``brdf_io.export_formats``), and
#: the options that set them. Each library word is spelt so that it occurs in no other message.
OPTION_OF: tuple[tuple[str, str], ...] = (
    ("max_F/max_P", "--max-F/--max-P"),
    ("layer=NAME", "--env-layer NAME"),
    ("part=NAME|INDEX", "--env-part NAME|INDEX"),
    ("name=FORMAT", "--to FORMAT"),
)
#: ``render.error_image.check_error_image_request``'s words as ``shrm render`` says them (applied
#: to that check's messages only: ``mode=`` is too common a word for every message).
ERROR_IMAGE_TERMS: tuple[tuple[str, str], ...] = (
    ("the error image path", "--error-image"),
    ("an error image", "--error-image"),
    ("mode=", "--mode "),
)


def in_cli_terms(text: str, terms: tuple[tuple[str, str], ...] = ()) -> str:
    """``text``, a library message, as the command line says it: each (library words, option) pair
    of ``terms`` (the caller's, replaced first) and of :data:`OPTION_OF` replaced in turn.

    >>> in_cli_terms("ε(F0, P0) > tol: raise max_F/max_P")
    'ε(F0, P0) > tol: raise --max-F/--max-P'
    """
    for name, option in (*terms, *OPTION_OF):
        text = text.replace(name, option)
    return text
