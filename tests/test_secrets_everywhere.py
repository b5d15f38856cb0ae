"""No form of a secret anywhere one dataset run prints or writes: every printed line, every log record,
the summaries, the manifest and every output file (PNG text chunks and bytes, HTML, NPZ arrays, PLY headers).

The run reads an S3 object with credentials in ``storage_options``, a signed ``http://`` URL and a
``user:password@`` URL, through the CLI (``hht3d run`` of a pipeline) and from Python (``run_dataset``).
The oracle of "found" is :func:`helpers.secrets.forms_found` (every form, any letter case).  Each run is
made twice: with redaction switched off (every ``redact`` of hht3d replaced by the identity) the search
must find a secret, so that it can fail; with redaction on, it must find none anywhere.
"""

from __future__ import annotations

import io
import json
import logging
import struct
import sys
import zlib
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("s3fs", reason="the object-storage tests need s3fs (pip install -e '.[dev]')")
pytest.importorskip("moto.server", reason="the object-storage tests need moto[server] (pip install -e '.[dev]')")

import fsspec  # noqa: E402

from helpers.models import shipped_model_path  # noqa: E402
from helpers.secrets import forms_found  # noqa: E402
from helpers.servers import s3_server  # noqa: E402
from hht3d import redaction  # noqa: E402
from hht3d.cli import main  # noqa: E402
from hht3d.dataset import run_dataset  # noqa: E402

BUCKET = "secrets"
KEY_ID = "AKIDSECRETSEVERYWHERE1"
SECRET = "wJalrSecretEverywhere/K7MDENG+bPxRfiCY"
SIGNATURE = "5ca1ab1e0ddba11f00dfacade5ca1ab1e0ddba11f00dfacade"
PASSWORD = "pw4everywhereTest9"
SECRETS = {"storage secret": SECRET, "key id": KEY_ID, "signature": SIGNATURE, "password": PASSWORD}
PIPELINE = """\
version: 1
storage_options:
  s3: {{client_kwargs: {{endpoint_url: "{endpoint}"}}}}
  http: {{}}
inputs: {inputs}
steps:
  - {{op: signal, params: {{kind: mean_curvature}}}}
  - {{op: hht, params: {{max_imfs: 2}}}}
outputs:
  folder: {folder}
  files:
    - {{path: "{{stem}}_hht.npz"}}
    - {{path: "{{stem}}_hht.ply"}}
    - {{path: "{{stem}}_hht.png"}}
    - {{path: "{{stem}}_hht.html"}}
"""


@pytest.fixture(scope="module")
def store():
    """``(endpoint, fs)``: moto with the scans."""
    with s3_server("moto") as endpoint:
        fs = fsspec.filesystem("s3", client_kwargs={"endpoint_url": endpoint})
        fs.mkdir(BUCKET)
        fs.put_file(str(shipped_model_path("spot.ply")), f"{BUCKET}/scans/spot.ply")
        fs.put_file(str(shipped_model_path("sphere_oct4098.ply")), f"{BUCKET}/scans/sphere.ply")
        fs.put_file(str(shipped_model_path("spot.ply")), f"{BUCKET}/shared/cow.ply")
        yield endpoint, fs


def _inputs(endpoint: str) -> list[str]:
    """An S3 object, a signed http URL and a ``user:password@`` URL."""
    host = endpoint.split("://", 1)[1]
    credential = f"{KEY_ID}%2F20261203%2Fus-east-1%2Fs3%2Faws4_request"
    return [
        f"s3://{BUCKET}/scans/spot.ply",
        f"{endpoint}/{BUCKET}/scans/sphere.ply?X-Amz-Credential={credential}&X-Amz-Signature={SIGNATURE}&X-Amz-Expires=600",
        f"http://scanner:{PASSWORD}@{host}/{BUCKET}/shared/cow.ply",
    ]


class _Records(logging.Handler):
    def __init__(self):
        super().__init__(logging.DEBUG)
        self.lines: list[str] = []

    def emit(self, record):
        self.lines.append(record.getMessage())


def _png_text(data: bytes) -> str:
    """The text of a PNG's tEXt, zTXt and iTXt chunks (a minimal chunk reader)."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    texts, at = [], 8
    while at < len(data):
        (length,), kind = struct.unpack(">I", data[at : at + 4]), data[at + 4 : at + 8]
        body = data[at + 8 : at + 8 + length]
        at += 12 + length
        if kind == b"tEXt":
            texts.append(body.decode("latin-1"))
        elif kind == b"zTXt":
            key, _, rest = body.partition(b"\0")
            texts.append(key.decode("latin-1") + " " + zlib.decompress(rest[1:]).decode("latin-1"))
        elif kind == b"iTXt":
            key, _, rest = body.partition(b"\0")
            compressed, rest = rest[0], rest[2:]
            _, _, rest = rest.partition(b"\0")  # language
            _, _, text = rest.partition(b"\0")  # translated keyword
            texts.append(key.decode("latin-1") + " " + (zlib.decompress(text) if compressed else text).decode("utf-8"))
    return "\n".join(texts)


def _npz_text(data: bytes) -> str:
    """Every NPZ array's name, dtype and shape, and the values of its text and object arrays."""
    parts = []
    with np.load(io.BytesIO(data), allow_pickle=False) as npz:
        for name in npz.files:
            array = npz[name]
            parts.append(f"{name} {array.dtype} {array.shape}")
            if array.dtype.kind in "USO":
                parts.append(" ".join(map(str, array.ravel().tolist())))
    return "\n".join(parts)


def _views(name: str, data: bytes) -> dict[str, str | bytes]:
    """What a file holds, as texts a secret could hide in: its bytes, and its format's metadata."""
    views: dict[str, str | bytes] = {"bytes": data}
    suffix = Path(name).suffix.lower()
    if suffix == ".png":
        views["text chunks"] = _png_text(data)
    elif suffix == ".npz":
        views["arrays"] = _npz_text(data)
    elif suffix == ".ply":
        views["header"] = data[: data.find(b"end_header")].decode("latin-1")
    return views


def _unredacted(monkeypatch) -> None:
    """Switch redaction off: every module of hht3d that holds ``redact`` gets the identity."""
    real = redaction.redact
    for module in list(sys.modules.values()):
        if getattr(module, "__name__", "").startswith("hht3d") and getattr(module, "redact", None) is real:
            monkeypatch.setattr(module, "redact", str)


def _everything(store, tmp_path, capfd, monkeypatch) -> dict[str, str | bytes]:
    """Run the dataset by the CLI and from Python; every place a secret could be, by name."""
    endpoint, fs = store
    inputs = _inputs(endpoint)
    records = _Records()
    logger = logging.getLogger("hht3d")
    logger.addHandler(records)
    level = logger.level
    logger.setLevel(logging.DEBUG)
    monkeypatch.setenv("AWS_ACCESS_KEY_ID", KEY_ID)
    monkeypatch.setenv("AWS_SECRET_ACCESS_KEY", SECRET)
    cli_out = tmp_path / "cli-out"
    pipeline = tmp_path / "p.yaml"
    pipeline.write_text(PIPELINE.format(endpoint=endpoint, inputs=json.dumps(inputs), folder=cli_out))
    try:
        code = main(["run", str(pipeline), "--scheduler", "synchronous", "--log-level", "debug"])
        options = {
            "s3": {"key": KEY_ID, "secret": SECRET, "client_kwargs": {"endpoint_url": endpoint}},
            "http": {},
        }
        rows = run_dataset(
            inputs,
            f"s3://{BUCKET}/py-out",
            storage_options=options,
            scheduler="synchronous",
            progress=True,
            max_imfs=2,
        )
    finally:
        logger.removeHandler(records)
        logger.setLevel(level)
    assert code == 0 and [r.status for r in rows] == ["ok", "ok", "ok"], [r.error for r in rows]
    printed = capfd.readouterr()
    places: dict[str, str | bytes] = {
        "stdout": printed.out,
        "stderr": printed.err,
        "log records": "\n".join(records.lines),
    }
    for path in sorted(p for p in cli_out.rglob("*") if p.is_file()):
        for view, text in _views(path.name, path.read_bytes()).items():
            places[f"cli-out/{path.name} ({view})"] = text
    fs.invalidate_cache()
    for key in sorted(fs.find(f"{BUCKET}/py-out")):
        for view, text in _views(key, fs.cat_file(key)).items():
            places[f"{key} ({view})"] = text
    return places


def _found(places: dict) -> dict[str, list[str]]:
    return {
        f"{where}: {what}": found
        for where, text in places.items()
        for what, secret in SECRETS.items()
        if (found := forms_found(text, secret))
    }


def test_with_redaction_off_the_search_finds_the_secrets(store, tmp_path, capfd, monkeypatch):
    """The search can fail: unredacted, the signed URL's credential and signature and the URL's password
    are in the printed rows and in both runs' summaries."""
    _unredacted(monkeypatch)
    found = {where.rsplit(": ", 1)[0] for where in _found(_everything(store, tmp_path, capfd, monkeypatch))}
    summaries = {
        f"{folder}/summary.{kind} (bytes)" for folder in ("cli-out", f"{BUCKET}/py-out") for kind in ("json", "csv")
    }
    assert found >= {"stdout"} | summaries


def test_no_form_of_a_secret_is_anywhere_a_run_prints_or_writes(store, tmp_path, capfd, monkeypatch):
    places = _everything(store, tmp_path, capfd, monkeypatch)
    assert _found(places) == {}
    assert "wrote" in places["stdout"]  # the places searched are not empty (these runs log no record: none is due)
    kinds = {"(text chunks)": "Matplotlib", "(arrays)": "laplacian", "(header)": "element vertex", ".html": "<script"}
    for ending, sign in kinds.items():
        views = [text for where, text in places.items() if ending in where]
        assert views and all(sign in str(text) for text in views), ending
