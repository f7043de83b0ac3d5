import numpy as np
import pytest

from algorithms.cases import disk
from algorithms.io import InputError, OutputExistsError, load_model, load_points, load_raw, save_mesh


@pytest.mark.parametrize("fmt", ["ply", "obj", "off"])
def test_round_trip_keeps_free_points(tmp_path, fmt):
    m = disk(segments=12, rings=2)
    free = np.array([[3.0, 0, 0], [3.5, 0.5, 0.1]])
    p = save_mesh(m, tmp_path / f"d.{fmt}", free_points=free)
    model = load_model(p)
    assert model.mesh.n_faces == m.n_faces
    np.testing.assert_allclose(np.sort(model.free_points, axis=0), np.sort(free, axis=0), atol=1e-6)
    np.testing.assert_allclose(model.mesh.vertices[model.mesh.faces], m.vertices[m.faces], atol=1e-6)


def test_stl_vertices_are_merged(tmp_path):
    m = disk(segments=12, rings=2)
    p = save_mesh(m, tmp_path / "d.stl")
    v, f = load_raw(p)
    assert len(v) == m.n_vertices and len(f) == m.n_faces


def test_a_nanometre_sized_stl_keeps_its_faces(tmp_path):
    """Merged by exact position, not by coordinates rounded to 9 decimals (the vertices of a model
    1e-9 across rounded to three points: every face degenerate, nothing left to repair)."""
    m = disk(segments=12, rings=2)
    p = save_mesh(type(m)(m.vertices * 1e-9, m.faces), tmp_path / "tiny.stl")
    v, f = load_raw(p)
    assert len(v) == m.n_vertices and len(f) == m.n_faces
    model = load_model(p)
    assert model.mesh.n_faces == m.n_faces and not model.set_aside


@pytest.mark.parametrize("fmt", ["ply", "obj"])
def test_a_triangle_soup_is_welded(tmp_path, fmt):
    """A PLY or OBJ with every triangle's corners written apart (a soup) reads as the surface it is:
    one island, its one border loop, not one island per triangle."""
    import trimesh

    m = disk(segments=12, rings=2)
    soup = m.vertices[m.faces].reshape(-1, 3)
    p = tmp_path / f"soup.{fmt}"
    trimesh.Trimesh(soup, np.arange(len(soup)).reshape(-1, 3), process=False).export(p)
    v, f = load_raw(p)
    assert len(f) == m.n_faces and len(v) == m.n_vertices
    np.testing.assert_allclose(v[f], m.vertices[m.faces], atol=1e-9)  # the same triangles, corner by corner
    from algorithms.topology import boundary_loops, islands

    assert islands(f)[0] == 1 and len(boundary_loops(f)) == 1


def test_never_overwrites(tmp_path):
    m = disk(segments=8, rings=1)
    p = save_mesh(m, tmp_path / "d.ply")
    before = p.read_bytes()
    with pytest.raises(OutputExistsError, match="--force"):
        save_mesh(disk(segments=9, rings=1), p)
    assert p.read_bytes() == before
    save_mesh(disk(segments=9, rings=1), p, force=True)
    assert p.read_bytes() != before


def test_point_cloud_files(tmp_path):
    xyz = tmp_path / "c.xyz"
    xyz.write_text("# x y z\n0 0 1\n1 2 3 0.5\n")
    np.testing.assert_allclose(load_points(xyz), [[0, 0, 1], [1, 2, 3]])
    m = load_model(save_mesh(disk(segments=8, rings=1), tmp_path / "d.ply"), points=xyz)
    assert m.free_point_counts() == {"total": 2, "unreferenced": 0, "from_set_aside_faces": 0,
                                     "point_cloud": 2}


@pytest.mark.parametrize("name,content,msg", [
    ("missing.ply", None, "no such file"),
    ("empty.ply", b"", "empty"),
    ("x.dae", b"abc", "unknown mesh format"),
    ("bad.obj", b"v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n", "NaN"),
    ("range.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", "out of range"),
    ("garbage.ply", b"ply\nformat binary_little_endian 1.0\nelement vertex 99\nend_header\n\x00\x01", "cannot read"),
    ("nothing.obj", b"# only a comment\n", "no vertices"),
    ("header_only.ply", b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n", "truncated"),
])
def test_bad_inputs_name_file_and_problem(tmp_path, name, content, msg):
    p = tmp_path / name
    if content is not None:
        p.write_bytes(content)
    with pytest.raises(InputError) as e:
        load_model(p)
    assert name in str(e.value) and msg in str(e.value)
