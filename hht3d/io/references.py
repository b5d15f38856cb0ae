"""Files that a scan refers to, checked before Open3D follows the references.

A ``.gltf`` (and the JSON chunk of a ``.glb``) names its buffers and images
by URI, and an ``.obj`` its material libraries (``mtllib``), whose texture
maps (``map_Kd`` ...) name images.  Open3D reads whatever they name, so a
scan could turn ``/etc/passwd`` into vertex coordinates, or hang on a FIFO.
A reference is allowed only to a file inside the scan's own folder (``data:``
URIs are fine); anything else is refused before Open3D reads the scan.

Each reference is checked as the reading library may take it, not as a URL
parser would: a glTF URI's query or fragment (``inside.bin?/../../x.bin``) and
a backslash (``..\\outside\\evil.mtl``) are refused outright, since Open3D's
readers treat them as part of the path; an OBJ or MTL file name may hold
spaces, so every tail of a directive's words (``../outside/a b.png``, then
``b.png``) must stay inside.
"""

from __future__ import annotations

import json
import os
import struct
from collections.abc import Collection
from pathlib import Path
from urllib.parse import unquote, urlsplit

from ..errors import InputError, shown
from .formats import short
from .paths import confined

__all__ = ["check_references"]

#: The most bytes of a glTF's JSON (or of an OBJ's / MTL's text) read to find its references.
MAX_SCAN = 64 << 20


def check_references(path: Path) -> None:
    """Refuse a scan whose external references leave its folder (glTF, GLB, OBJ and its MTL files).

    Raises
    ------
    InputError
        Naming the scan and the reference.
    """
    ext = path.suffix.lower()
    if ext in (".gltf", ".glb"):
        for uri in _gltf_uris(path, binary=ext == ".glb"):
            if uri.startswith("data:"):
                continue
            parts = urlsplit(uri)
            if parts.scheme:
                _inside(path, uri, None)
            elif "?" in uri or "#" in uri:
                _inside(path, uri, None, problem=_AMBIGUOUS)
            _inside(path, uri, unquote(uri))
    elif ext == ".obj":
        for names in _directives(path, ("mtllib",)):
            for name in {names, *names.split()}:  # one name with spaces, or several names
                target = _inside(path, name, name, required=False)
                if os.path.isfile(target):
                    for image in _directives(target, ("map_", "bump", "disp", "decal", "refl", "norm")):
                        for tail in _tails(image):
                            _inside(path, image, tail, required=False)


def _tails(argument: str) -> list[str]:
    """Every file name a directive's argument may mean: the words from each one to the end
    (options such as ``-s 1 1 1`` come first, and a name may hold spaces)."""
    words = argument.split()
    return [" ".join(words[i:]) for i in range(len(words))]


#: Why a reference with a query, a fragment or a backslash is refused.
_AMBIGUOUS = "a name with '?', '#' or '\\', which the readers take as part of a path that may leave the folder"


def _inside(
    scan: Path, reference: str, target: str | None, required: bool = True, problem: str = "outside the file's folder"
) -> Path:
    """The referenced file, if it lies inside the scan's folder and is a regular file (or, unless
    ``required``, is missing: Open3D then skips it); else an :class:`InputError` saying ``problem``
    for a reference that cannot be checked (``target`` None) or leaves the folder."""
    if target is not None and "\\" in target:  # a separator on Windows, a name character elsewhere
        target, problem = None, _AMBIGUOUS
    resolved = None if target is None or os.path.isabs(target) else scan.parent / target
    if resolved is not None and confined(resolved, scan.parent) is not None:
        if os.path.exists(resolved) and not os.path.isfile(resolved):
            problem = "not a regular file"
        elif required and not os.path.exists(resolved):
            problem = "a missing file"
        else:
            return resolved
    raise InputError(
        f"{short(scan)}: refers to {shown(reference)}, {problem}; a scan may only refer to "
        "files beside it (or embed them)"
    )


def _gltf_uris(path: Path, binary: bool) -> list[str]:
    try:
        with open(path, "rb") as handle:
            if binary:
                header = handle.read(20)
                if len(header) < 20 or header[:4] != b"glTF":
                    raise InputError(f"{short(path)}: not a GLB file (no glTF header)")
                length, kind = struct.unpack("<II", header[12:20])
                if kind != 0x4E4F534A:  # "JSON"
                    raise InputError(f"{short(path)}: not a GLB file (its first chunk is not JSON)")
                text = handle.read(min(length, MAX_SCAN))
            else:
                text = handle.read(MAX_SCAN)
        document = json.loads(text)
    except OSError as exc:
        raise InputError(f"{short(path)}: cannot read ({exc.strerror})") from None
    except ValueError as exc:
        raise InputError(f"{short(path)}: not a readable glTF file ({exc})") from None
    if not isinstance(document, dict):
        raise InputError(f"{short(path)}: not a readable glTF file (not a JSON object)")
    uris = []
    for key in ("buffers", "images"):
        items = document.get(key) or []
        for item in items if isinstance(items, list) else []:
            if isinstance(item, dict) and "uri" in item:
                if not isinstance(item["uri"], str):
                    raise InputError(f"{short(path)}: a {key[:-1]} uri is not a string")
                uris.append(item["uri"])
    return uris


def _directives(path: Path | str, keywords: Collection[str]) -> list[str]:
    """The arguments of the lines of a text file (OBJ, MTL) starting with one of ``keywords``."""
    found = []
    try:
        with open(path, "rb") as handle:
            text = handle.read(MAX_SCAN).decode("utf-8", "replace")
    except OSError as exc:
        raise InputError(f"{short(path)}: cannot read ({exc.strerror})") from None
    for line in text.splitlines():
        words = line.strip().split(None, 1)
        if len(words) == 2 and words[0].startswith(tuple(keywords)):
            found.append(words[1].strip())
    return found
