"""URL inputs as users write them: signed URLs, other protocols' names, one run mixing stores, saved
results read back from a bucket (hht3d.io.storage, hht3d.results).

Oracles: an S3 server (moto, on 127.0.0.1) that signs URLs itself (``s3fs.S3FileSystem.sign``),
the shipped model's vertex count, and tests/helpers/secrets.py for what a message may not hold.
"""

from __future__ import annotations

import fsspec
import pytest
from fsspec.implementations.memory import MemoryFileSystem

import hht3d
from helpers.models import shipped_model_path
from helpers.secrets import forms_found
from hht3d.cli import main
from hht3d.errors import InputError
from hht3d.geometry.signals import mean_curvature
from hht3d.io import storage

pytest.importorskip("s3fs", reason="needs s3fs (pip install -e '.[dev]')")
pytest.importorskip("moto.server", reason="needs moto[server] (pip install -e '.[dev]')")

from helpers.servers import s3_server  # noqa: E402

BUCKET = "signed"
SPOT = shipped_model_path("spot.ply")


@pytest.fixture(scope="module")
def signed():
    """``(endpoint, options, signed URL of spot.ply, fs)`` on a moto S3 server."""
    with s3_server() as endpoint:
        options = {"client_kwargs": {"endpoint_url": endpoint}}
        fs = fsspec.filesystem("s3", **options)
        fs.mkdir(BUCKET)
        fs.put_file(str(SPOT), f"{BUCKET}/scans/spot.ply")
        fs.put_file(str(SPOT), f"{BUCKET}/scans/spot.txt")
        yield endpoint, options, fs.sign(f"{BUCKET}/scans/spot.ply", expiration=3600), fs


def _pipeline(tmp_path) -> str:
    path = tmp_path / "p.yaml"
    path.write_text(
        "version: 1\ninputs: x.ply\nsteps:\n  - {op: signal, params: {kind: mean_curvature}}\n"
        f"  - {{op: emd, params: {{max_imfs: 1}}}}\noutputs:\n  folder: {tmp_path / 'out'}\n"
        "  files: [{path: '{stem}_emd.npz'}]\n"
    )
    return str(path)


def test_a_signed_url_is_an_input_like_any_file(signed, tmp_path, capfd):
    """Its suffix is read from the path, not from the query that carries the signature."""
    _, _, url, _ = signed
    assert "Signature=" in url
    assert hht3d.load(url).n_vertices == 2930
    assert main(["validate", _pipeline(tmp_path), "--set", f"inputs={url}"]) == 0
    out, err = capfd.readouterr()
    signature = url.split("Signature=")[1].split("&")[0]
    assert err == "" and not forms_found(out, signature)


def test_a_signed_url_with_a_wrong_suffix_names_no_signature(signed, tmp_path, capfd):
    _, _, _, fs = signed
    wrong = fs.sign(f"{BUCKET}/scans/spot.txt", expiration=3600)
    assert main(["validate", _pipeline(tmp_path), "--set", f"inputs={wrong}"]) == 1
    err = capfd.readouterr().err
    signature = wrong.split("Signature=")[1].split("&")[0]
    assert "unknown extension '.txt'" in err and not forms_found(err, signature), err


def test_options_keyed_by_protocol_serve_a_run_that_mixes_stores(signed):
    """S3 options (an endpoint) given to an https:// client fail inside it; keyed by protocol,
    each URL gets its own, and one set for all says how to key them."""
    _, options, url, _ = signed
    mixed = {"s3": options, "http": {}}
    assert hht3d.load(url, storage_options=mixed).n_vertices == 2930
    assert hht3d.load(f"s3://{BUCKET}/scans/spot.ply", storage_options=mixed).n_vertices == 2930
    with pytest.raises(InputError, match="key them by protocol"):
        hht3d.load(url, storage_options=options)


def test_a_saved_result_is_read_back_from_a_bucket(signed):
    _, options, _, _ = signed
    surface = hht3d.load(SPOT)
    result = hht3d.hht(surface, mean_curvature(surface), max_imfs=1)
    url = f"s3://{BUCKET}/results/spot_hht.npz"
    result.save(url, storage_options=options)
    again = hht3d.load_result(url, storage_options=options)
    assert again.n_imfs == 1 and (again.imfs == result.imfs).all() and again.surface.name == "spot_hht"
    with pytest.raises(InputError, match="no such object"):
        hht3d.load_result(f"s3://{BUCKET}/results/none_hht.npz", storage_options=options)


class _Aliased(MemoryFileSystem):
    """A back-end registered under two names, the first its own (as adlfs: ``abfs``, then ``az``)."""

    protocol = ("hht3dabfs", "hht3daz")

    @classmethod
    def _strip_protocol(cls, path):
        for name in cls.protocol:
            if path.startswith(f"{name}://"):
                path = "memory://" + path[len(name) + 3 :]
        return super()._strip_protocol(path)


def test_listed_inputs_keep_the_protocol_the_user_wrote():
    fsspec.register_implementation("hht3dabfs", _Aliased, clobber=True)
    fsspec.register_implementation("hht3daz", _Aliased, clobber=True)
    fs = _Aliased()
    fs.pipe_file("/container/scans/a.ply", b"ply")
    assert storage.resolve_locations("hht3daz://container/scans/*.ply") == ["hht3daz:///container/scans/a.ply"]
