"""LAS and LAZ (hht3d.io.las): files written by laspy, read by hht3d, written back and read by laspy again.

The oracle is laspy's own read: coordinates are compared as the integers the file stores (exact at
its scale, with offsets of 10⁶ m), dimensions as their stored values.
"""

import sys
import textwrap

import numpy as np
import pytest

from hht3d import hht, load
from hht3d.errors import InputError, PipelineError
from hht3d.geometry.signals import signal
from hht3d.io import las as las_module
from hht3d.io import write_las
from hht3d.output_formats import FORMATS
from hht3d.pipeline import parse_pipeline, run_pipeline

laspy = pytest.importorskip("laspy")

OFFSETS = np.array([512_000.0, 5_400_000.0, 250.0])  # a UTM-like datum: 10⁶ m from the origin


def scan(path, n=900, *, point_format=3, seed=0):
    """A wavy patch of ``n`` points 10⁶ m from the origin, at millimetre scale, with intensity,
    classes 2 (x < 5) and 6, RGB and an extra-bytes dimension with a space in its name."""
    rng = np.random.default_rng(seed)
    u, v = rng.uniform(0, 10, n), rng.uniform(0, 10, n)
    header = laspy.LasHeader(point_format=point_format, version="1.4")
    header.offsets, header.scales = OFFSETS, np.full(3, 0.001)
    header.add_extra_dims([laspy.ExtraBytesParams("echo width", type=np.float32)])
    data = laspy.LasData(header)
    data.x, data.y = OFFSETS[0] + 1234.5678 + u, OFFSETS[1] + v
    data.z = OFFSETS[2] + np.sin(u) + 0.2 * np.cos(2 * v)
    data.intensity = (1000 + 400 * np.sin(3 * u)).astype(np.uint16)
    data.classification = np.where(u < 5, 2, 6).astype(np.uint8)
    data.return_number = rng.integers(1, 3, n).astype(np.uint8)
    data.gps_time = 3e8 + np.arange(n) * 1e-5
    data.red, data.green, data.blue = (rng.integers(0, 65536, (3, n))).astype(np.uint16)
    data["echo width"] = rng.uniform(0, 4, n).astype(np.float32)
    data.write(str(path))
    return laspy.read(str(path))


@pytest.mark.parametrize("suffix", [".las", ".laz"])
def test_a_scan_round_trips_exactly_at_its_scale(tmp_path, suffix):
    original = scan(tmp_path / f"scan{suffix}")
    surface = load(tmp_path / f"scan{suffix}", clean=False)
    assert not surface.is_mesh and surface.n_vertices == len(original.points)
    # local coordinates near 0, the file's frame through the origin; the integers exact
    assert np.abs(surface.vertices).max() < 20
    np.testing.assert_array_equal(
        np.round((surface.vertices + surface.origin - OFFSETS) / 0.001),
        np.column_stack([original.X, original.Y, original.Z]),
    )
    for name in ("intensity", "classification", "return_number", "gps_time"):
        np.testing.assert_array_equal(surface.attributes[name], np.asarray(original[name]), err_msg=name)
    np.testing.assert_array_equal(surface.attributes["echo_width"], original["echo width"])
    rgb = np.column_stack([original.red, original.green, original.blue]) / 65535
    np.testing.assert_allclose(surface.attributes["luminance"], rgb @ [0.2126, 0.7152, 0.0722], rtol=1e-12)

    path = write_las(tmp_path / f"back{suffix}", surface, {"wave": surface.vertices[:, 2]})
    with laspy.open(str(path)) as reader:
        assert reader.header.are_points_compressed == (suffix == ".laz")
    written = laspy.read(str(path))
    assert written.header.point_format.id == 3 and np.array_equal(written.header.offsets, OFFSETS)
    for name in original.point_format.dimension_names:
        np.testing.assert_array_equal(np.asarray(written[name]), np.asarray(original[name]), err_msg=name)
    np.testing.assert_array_equal(written["wave"], surface.vertices[:, 2])
    assert "luminance" not in written.point_format.dimension_names  # derived from RGB, not written


def test_chunks_and_the_classes_filter_read_what_laspy_reads(tmp_path, monkeypatch):
    monkeypatch.setattr(las_module, "CHUNK_POINTS", 128)  # 900 points: 8 chunks, the last one short
    original = scan(tmp_path / "scan.laz")
    ground = np.asarray(original.classification) == 2
    surface = load(tmp_path / "scan.laz", clean=False, classes=[2])
    assert surface.n_vertices == ground.sum()
    np.testing.assert_array_equal(surface.attributes["intensity"], np.asarray(original.intensity)[ground])
    np.testing.assert_array_equal(
        np.round((surface.vertices + surface.origin - OFFSETS) / 0.001),
        np.column_stack([original.X, original.Y, original.Z])[ground],
    )
    assert load(tmp_path / "scan.laz", clean=False, classes=[2, 6]).n_vertices == len(original.points)


def _spy_on_open(monkeypatch):
    """The readers laspy.open gives hht3d, and the LAZ backends it was asked for."""
    opened = []
    real = laspy.open

    def spy(*args, **kwargs):
        reader = real(*args, **kwargs)
        opened.append((reader, kwargs.get("laz_backend")))
        return reader

    monkeypatch.setattr(laspy, "open", spy)
    return opened


def _local_integers(surface):
    return np.round((surface.vertices + surface.origin - OFFSETS) / 0.001)


def test_the_parallel_decompressor_reads_in_chunks_what_laspy_reads(tmp_path, monkeypatch):
    """120,000 points: three of lazrs's 50,000-point chunks, read in 7,001-point pieces (none aligned)
    by the parallel decompressor; the oracle is laspy's single-threaded read."""
    scan(tmp_path / "scan.laz", n=120_000)
    original = laspy.read(str(tmp_path / "scan.laz"), laz_backend=laspy.LazBackend.Lazrs)
    monkeypatch.setattr(las_module, "CHUNK_POINTS", 7_001)
    opened = _spy_on_open(monkeypatch)
    surface = load(tmp_path / "scan.laz", clean=False)
    ((reader, backends),) = opened
    assert backends[0] == laspy.LazBackend.LazrsParallel
    assert type(reader.point_source.decompressor).__name__ == "ParLasZipDecompressor"
    np.testing.assert_array_equal(_local_integers(surface), np.column_stack([original.X, original.Y, original.Z]))
    for name in las_module._attribute_dimensions(original.point_format):
        values = surface.attributes[name.replace(" ", "_")]
        np.testing.assert_array_equal(values, np.asarray(original[name]), err_msg=name)
    rgb = np.column_stack([original.red, original.green, original.blue])
    np.testing.assert_array_equal(surface.colors, rgb / 65535)


def test_a_subset_of_dimensions_with_the_classes_filter_keeps_what_laspy_reads(tmp_path, monkeypatch):
    monkeypatch.setattr(las_module, "CHUNK_POINTS", 128)  # 900 points: 8 chunks, each with both classes
    original = scan(tmp_path / "scan.laz")
    building = np.asarray(original.classification) == 6
    surface = load(tmp_path / "scan.laz", clean=False, classes=[6], dimensions=["echo width", "gps_time", "luminance"])
    assert sorted(surface.attributes) == ["echo_width", "gps_time", "luminance"]
    assert surface.n_vertices == building.sum() > 0
    integers = np.column_stack([original.X, original.Y, original.Z])[building]
    np.testing.assert_array_equal(_local_integers(surface), integers)
    np.testing.assert_array_equal(surface.attributes["echo_width"], np.asarray(original["echo width"])[building])
    np.testing.assert_array_equal(surface.attributes["gps_time"], np.asarray(original.gps_time)[building])
    rgb = np.column_stack([original.red, original.green, original.blue])[building] / 65535
    np.testing.assert_array_equal(surface.colors, rgb)
    np.testing.assert_allclose(surface.attributes["luminance"], rgb @ [0.2126, 0.7152, 0.0722], rtol=1e-12)

    # without luminance the colours are not read; written back, the dimensions not kept are 0
    surface = load(tmp_path / "scan.laz", clean=False, classes=[6], dimensions=["intensity"])
    assert list(surface.attributes) == ["intensity"] and surface.colors is None
    written = laspy.read(str(write_las(tmp_path / "back.laz", surface)))
    np.testing.assert_array_equal(written.X, np.asarray(original.X)[building])
    np.testing.assert_array_equal(written.intensity, np.asarray(original.intensity)[building])
    assert not np.any(written.gps_time) and not np.any(written.red)


def test_a_subset_of_a_las_1_4_laz_decodes_only_its_layers_and_reads_what_laspy_reads(tmp_path, monkeypatch):
    """Point format 8 (RGB and NIR) and an extra-bytes dimension, every dimension random: each one read
    alone, lazrs decoding only its layer (and x, y, z), equals laspy's full read; so do a subset with the
    classes filter (which decodes the classification too)."""
    rng = np.random.default_rng(2)
    n = 600
    header = laspy.LasHeader(point_format=8, version="1.4")
    header.offsets, header.scales = OFFSETS, np.full(3, 0.001)
    header.add_extra_dims([laspy.ExtraBytesParams("echo width", type=np.float32)])
    data = laspy.LasData(header)
    data.x, data.y, data.z = (OFFSETS[:, None] + rng.uniform(0, 10, (3, n))).astype(np.float64)
    for dimension in data.point_format.dimensions:
        if dimension.name not in ("X", "Y", "Z"):
            kind = np.dtype(dimension.dtype or np.uint8)  # bit fields: small unsigned integers
            values = rng.uniform(0, 1, n) if kind.kind == "f" else rng.integers(1, 2 ** min(dimension.num_bits, 15), n)
            data[dimension.name] = values.astype(kind)
    data.classification = rng.choice([2, 6], n).astype(np.uint8)
    data.write(str(tmp_path / "scan.laz"))
    original = laspy.read(str(tmp_path / "scan.laz"))
    opened = _spy_on_open(monkeypatch)
    selection = laspy.DecompressionSelection
    full = load(tmp_path / "scan.laz", clean=False)
    assert opened[-1][0].decompression_selection == selection.all() & ~selection.WAVEPACKET  # format 8's layers
    for name in full.attributes:
        surface = load(tmp_path / "scan.laz", clean=False, dimensions=[name])
        if name == "luminance":
            np.testing.assert_array_equal(surface.colors, full.colors)
        else:
            dimension = "echo width" if name == "echo_width" else name
            np.testing.assert_array_equal(surface.attributes[name], np.asarray(original[dimension]), err_msg=name)
        np.testing.assert_array_equal(_local_integers(surface), np.column_stack([original.X, original.Y, original.Z]))
    assert opened[-1][0].decompression_selection == selection.base() | selection.Z | selection.RGB  # luminance
    ground = np.asarray(original.classification) == 2
    surface = load(tmp_path / "scan.laz", clean=False, classes=[2], dimensions=["gps_time", "echo width"])
    assert opened[-1][0].decompression_selection == (
        selection.base() | selection.Z | selection.GPS_TIME | selection.ALL_EXTRA_BYTES | selection.CLASSIFICATION
    )
    np.testing.assert_array_equal(surface.attributes["gps_time"], np.asarray(original.gps_time)[ground])
    np.testing.assert_array_equal(surface.attributes["echo_width"], np.asarray(original["echo width"])[ground])


def test_bytes_per_point_is_the_memory_of_the_kept_arrays(tmp_path):
    original = scan(tmp_path / "scan.las")
    point_format = original.point_format  # format 3 and one extra-bytes dimension: 14 scalars and RGB
    for dimensions, expected in ((None, 8 * (3 + 14 + 4)), (["intensity", "classification"], 8 * 5)):
        data = las_module.read_las(tmp_path / "scan.las", dimensions=dimensions)
        kept = [data["vertices"], *data["attributes"].values(), *([data["colors"]] if "colors" in data else [])]
        assert sum(a.nbytes for a in kept) / 900 == las_module.bytes_per_point(point_format, dimensions) == expected


def test_a_pipeline_keeps_the_dimensions_it_names(tmp_path):
    scan(tmp_path / "scan.laz", n=300)

    def run(dimensions):
        text = textwrap.dedent(f"""\
            version: 1
            execution: {{scheduler: synchronous, progress: false}}
            inputs: {tmp_path / "scan.laz"}
            steps:
              - {{id: load, op: load, params: {{dimensions: {dimensions}, clean: false}}}}
              - {{id: intensity, op: signal, params: {{kind: stored, attribute: intensity}}}}
            outputs:
              folder: {tmp_path / "out"}
              files:
                - {{from: load, path: "{{stem}}.ply"}}
            """)
        (row,) = run_pipeline(parse_pipeline(text))
        return row

    row = run("[intensity, classification]")
    assert row.status == "ok", row.error
    assert sorted(load(tmp_path / "out" / "scan.ply", clean=False).attributes) == ["classification", "intensity"]
    row = run("[intensity, nir]")
    assert row.status == "failed" and "\n" not in row.error
    assert row.error.endswith(
        "scan.laz: no dimension 'nir' in point format 3; its dimensions: intensity, return_number, "
        "number_of_returns, scan_direction_flag, edge_of_flight_line, classification, synthetic, key_point, "
        "withheld, scan_angle_rank, user_data, point_source_id, gps_time, echo_width, luminance"
    )
    with pytest.raises(PipelineError, match="parameter dimensions must be a list of names; got 'intensity'"):
        parse_pipeline(
            textwrap.dedent(f"""\
            version: 1
            inputs: {tmp_path / "scan.laz"}
            steps: [{{id: load, op: load, params: {{dimensions: intensity}}}}]
            """)
        )


def test_a_result_saved_as_npz_keeps_the_scan_origin(tmp_path):
    """A LAS scan 10⁶ m from its datum: its .npz result read back (load_result, and the viewer's
    read_fields) lies where laspy reads the scan, and is written back there."""
    from hht3d.results import load_result
    from hht3d.viz.saved import read_fields

    original = scan(tmp_path / "scan.las", n=400)
    surface = load(tmp_path / "scan.las", clean=False)
    result = hht(surface, signal(surface, "stored", attribute="intensity"), max_imfs=1)
    path = result.save(tmp_path / "scan_hht.npz")
    again = load_result(path)
    np.testing.assert_array_equal(again.surface.origin, surface.origin)
    written = laspy.read(str(write_las(tmp_path / "again.las", again.surface)))  # a new header: its own scale
    np.testing.assert_allclose(written.xyz, original.xyz, rtol=0, atol=0.001)
    shown, fields, _ = read_fields(path)
    np.testing.assert_allclose(shown.vertices + shown.origin, original.xyz, rtol=0, atol=1e-6)
    assert "origin" not in fields


def test_a_pipeline_filters_classes_reads_intensity_and_writes_imfs_as_extra_bytes(tmp_path):
    original = scan(tmp_path / "scan.laz", n=700)
    text = textwrap.dedent(f"""\
        version: 1
        execution: {{scheduler: synchronous, progress: false}}
        inputs: {tmp_path / "scan.laz"}
        steps:
          - {{id: load, op: load, params: {{classes: [2, 6], clean: false}}}}
          - {{id: intensity, op: signal, params: {{kind: stored, attribute: intensity}}}}
          - {{id: hht, op: hht, params: {{max_imfs: 1}}}}
        outputs:
          folder: {tmp_path / "out"}
          files:
            - {{from: hht, path: "{{stem}}_hht.laz", precision: float32}}
        """)
    (row,) = run_pipeline(parse_pipeline(text))
    assert row.status == "ok", row.error
    written = laspy.read(str(tmp_path / "out" / "scan_hht.laz"))
    surface = load(tmp_path / "scan.laz", clean=False)
    result = hht(surface, signal(surface, "stored", attribute="intensity"), max_imfs=1)
    np.testing.assert_array_equal(written.X, original.X)
    np.testing.assert_array_equal(written.intensity, original.intensity)
    for name in ("signal", "residue", "imf_1", "amplitude_1", "frequency_1"):
        assert written.point_format.dimension_by_name(name).dtype == np.float32, name
        expected = result.vertex_attributes()[name].astype(np.float32)
        np.testing.assert_allclose(written[name], expected, rtol=1e-5, atol=1e-5 * np.abs(expected).max(), err_msg=name)


def test_a_filtered_scan_is_written_back_in_its_frame(tmp_path):
    from hht3d.apps import filter_geometry
    from hht3d.apps.filters import LowPass

    original = scan(tmp_path / "scan.las", n=400)
    surface = load(tmp_path / "scan.las", clean=False)
    result = hht(surface, signal(surface, "mean_curvature"), max_imfs=1)
    smoothed = filter_geometry(result, LowPass(cutoff=1.0))
    written = laspy.read(str(FORMATS["surface"]["las"].write(smoothed, surface, tmp_path / "smooth.las")))
    moved = np.abs(written.xyz - original.xyz).max()
    assert 0 < moved < 1  # moved by the filter, not by 10⁶ m
    np.testing.assert_array_equal(written.intensity, original.intensity)


def test_a_mesh_written_as_las_keeps_its_points_at_the_chosen_scale(tmp_path, sphere):
    path = FORMATS["surface"]["las"].write(sphere, sphere, tmp_path / "sphere.las", precision="float64")
    written = laspy.read(str(path))
    scale = written.header.scales[0]
    assert scale <= 1e-6 * sphere.bounding_box_diagonal
    np.testing.assert_allclose(written.xyz, sphere.vertices, rtol=0, atol=scale / 2 + 1e-12)


def test_hht3d_info_reports_the_points_classes_and_dimensions(tmp_path, capsys):
    import json

    from hht3d.cli import main

    original = scan(tmp_path / "scan.laz")
    assert main(["info", str(tmp_path / "scan.laz"), "--no-clean", "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    codes = np.asarray(original.classification)
    assert info["vertices"] == 900 and info["classes"] == {"2": int((codes == 2).sum()), "6": int((codes == 6).sum())}
    assert {"intensity", "return_number", "gps_time", "echo_width", "luminance"} <= set(info["attributes"])
    np.testing.assert_allclose(info["bounding_box_min"], original.header.mins, rtol=0, atol=1e-6)


def test_clear_errors(tmp_path, monkeypatch, sphere):
    scan(tmp_path / "scan.las")
    with pytest.raises(
        InputError,
        match=r"classes \[9\] keep 0 of 900 points; a surface needs at least 4 "
        r"\(the file's classes: 2, 6\)",
    ):
        load(tmp_path / "scan.las", classes=[9])
    with pytest.raises(InputError, match="classification codes"):
        load(tmp_path / "scan.las", classes=[256])
    from hht3d.io import write_ply

    for setting, value in (("classes", [2]), ("dimensions", ["intensity"])):
        with pytest.raises(InputError, match=f"load option {setting} is for .las, .laz files; this is .ply"):
            load(write_ply(tmp_path / "sphere.ply", sphere), **{setting: value})
    plain = laspy.LasData(laspy.LasHeader(point_format=1, version="1.4"))  # no RGB: no luminance
    plain.x, plain.y, plain.z = np.random.default_rng(1).uniform(0, 1, (3, 10))
    plain.write(str(tmp_path / "plain.las"))
    with pytest.raises(InputError, match=r"plain.las: no dimension 'luminance' in point format 1; .*gps_time$"):
        load(tmp_path / "plain.las", dimensions=["intensity", "luminance"])

    empty = laspy.LasData(laspy.LasHeader(point_format=0, version="1.4"))
    empty.write(str(tmp_path / "empty.las"))
    with pytest.raises(InputError, match="empty.las: the file holds no points"):
        load(tmp_path / "empty.las")

    data = bytearray((tmp_path / "scan.las").read_bytes())  # the header declares 900 points; keep 10
    cut = tmp_path / "cut.las"
    cut.write_bytes(data[: laspy.read(str(tmp_path / "scan.las")).header.offset_to_point_data + 10 * 38])
    with pytest.raises(InputError, match="declares 900 points of .* more than its .* bytes hold"):
        load(cut)
    scan(tmp_path / "scan.laz")  # a LAZ chunk table past the end, and a LAZ cut short
    data = bytearray((tmp_path / "scan.laz").read_bytes())
    start = laspy.read(str(tmp_path / "scan.laz")).header.offset_to_point_data
    (tmp_path / "cut.laz").write_bytes(data[: start + 200])
    data[start : start + 8] = (len(data) + 10**6).to_bytes(8, "little")  # where the chunk table is said to be
    (tmp_path / "table.laz").write_bytes(data)
    for name in ("table.laz", "cut.laz"):
        with pytest.raises(InputError, match=rf"{name}: the points cannot be read \(.*\)$"):
            load(tmp_path / name)
    (tmp_path / "junk.laz").write_bytes(b"LASF" + bytes(400))
    with pytest.raises(InputError, match="junk.laz: not a readable LAS/LAZ file"):
        load(tmp_path / "junk.laz")

    monkeypatch.setitem(sys.modules, "laspy", None)  # laspy not installed
    with pytest.raises(InputError, match=r"^LAS/LAZ files need laspy: pip install 'hht3d\[lidar\]'$"):
        load(tmp_path / "scan.las")


@pytest.mark.parametrize("suffix", [".las", ".laz"])
def test_a_real_scan_round_trips(tmp_path, shared_model, suffix):
    """The Kinect office frame (62,143 points with their real RGB) as a LAS 1.4 point format 7 scan
    10⁶ m from its datum at 0.01 mm, written by laspy; read and written back by hht3d, read by laspy."""
    from plyfile import PlyData

    vertex = PlyData.read(str(shared_model("office_kinect_colored.ply")))["vertex"].data
    header = laspy.LasHeader(point_format=7, version="1.4")
    header.offsets, header.scales = OFFSETS, np.full(3, 1e-5)
    data = laspy.LasData(header)
    data.x, data.y, data.z = (OFFSETS[k] + np.asarray(vertex[c], dtype=np.float64) for k, c in enumerate("xyz"))
    data.red, data.green, data.blue = (np.asarray(vertex[c], dtype=np.uint16) * 257 for c in ("red", "green", "blue"))
    data.intensity = np.arange(len(vertex), dtype=np.uint16)
    data.write(str(tmp_path / f"office{suffix}"))
    original = laspy.read(str(tmp_path / f"office{suffix}"))

    surface = load(tmp_path / f"office{suffix}", clean=False)
    assert surface.n_vertices == len(vertex) == 62_143
    np.testing.assert_array_equal(
        np.round((surface.vertices + surface.origin - OFFSETS) / 1e-5),
        np.column_stack([original.X, original.Y, original.Z]),
    )
    written = laspy.read(str(write_las(tmp_path / f"back{suffix}", surface)))
    for name in original.point_format.dimension_names:
        np.testing.assert_array_equal(np.asarray(written[name]), np.asarray(original[name]), err_msg=name)


def test_the_fig4_panel_and_the_viewer_take_a_las_scan(tmp_path):
    """Issue 36's target: a LAS input gives the composite figure (model, signal, each IMF and the
    residue, then frequency and amplitude under each IMF) and a viewer page whose IMF fields are the
    result's, with the scan's origin kept."""
    from helpers.pages import field_values, page_data
    from hht3d.viz.figures import hht_figure

    scan(tmp_path / "scan.las")
    surface = load(tmp_path / "scan.las")
    result = hht(surface, surface.attributes["intensity"], max_imfs=2)
    images = [ax for ax in hht_figure(result, panel_width=80).axes if ax.get_images()]
    assert len(images) == 2 + result.n_imfs + 1 + 2 * result.n_imfs
    page = page_data(result.to_html(tmp_path / "scan.html"))
    for k in range(result.n_imfs):
        np.testing.assert_allclose(field_values(page, f"imf_{k + 1}"), result.imfs[k], rtol=1e-6, atol=1e-6)
    np.testing.assert_array_equal(result.surface.origin, surface.origin)
    assert np.abs(surface.origin).max() > 1e5  # the scan lies 10⁶ m out, read near 0
