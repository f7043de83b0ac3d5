"""ASE export re-read by a small parser, and the `bridgefield frep` command."""

import json
import re

import numpy as np
import pytest

from algorithms.cli import main
from algorithms.frep.ase import ase_text, save_ase
from algorithms.frep.objects import demo_object, load_spec
from algorithms.frep.pipeline import triangulate_object
from algorithms.io import InputError, OutputExistsError, load_raw
from algorithms.mesh import Mesh


def parse_ase(text):
    """A minimal ASE reader: vertices, faces, face normals; checks the declared counts and braces."""
    assert text.startswith("*3DSMAX_ASCIIEXPORT")
    assert text.count("{") == text.count("}")
    nv = int(re.search(r"\*MESH_NUMVERTEX (\d+)", text).group(1))
    nf = int(re.search(r"\*MESH_NUMFACES (\d+)", text).group(1))
    verts = {int(i): [float(a), float(b), float(c)]
             for i, a, b, c in re.findall(r"\*MESH_VERTEX (\d+)\t(\S+)\t(\S+)\t(\S+)", text)}
    faces = {int(i): [int(a), int(b), int(c)]
             for i, a, b, c in re.findall(r"\*MESH_FACE (\d+):\tA: (\d+)\tB: (\d+)\tC: (\d+)", text)}
    normals = [[float(a), float(b), float(c)]
               for a, b, c in re.findall(r"\*MESH_FACENORMAL \d+\t(\S+)\t(\S+)\t(\S+)", text)]
    vnormals = re.findall(r"\*MESH_VERTEXNORMAL (\d+)\t", text)
    assert len(verts) == nv and len(faces) == nf and len(normals) == nf and len(vnormals) == 3 * nf
    v = np.array([verts[i] for i in range(nv)])
    f = np.array([faces[i] for i in range(nf)])
    return v, f, np.array(normals)


def test_ase_round_trip_tetrahedron():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    v2, f2, n = parse_ase(ase_text(Mesh(v, f), name='a "quoted" name'))
    assert np.array_equal(v2, v) and np.array_equal(f2, f)
    assert np.allclose(n[0], [0, 0, -1]) and np.allclose(np.linalg.norm(n, axis=1), 1)


def test_ase_of_a_triangulated_torus(tmp_path):
    r = triangulate_object(demo_object("torus"), qlev=4)
    p = save_ase(r.mesh, tmp_path / "t.ase", name="torus")
    v, f, _ = parse_ase(p.read_text())
    assert np.allclose(v, r.mesh.vertices, atol=1e-8) and np.array_equal(f, r.mesh.faces)
    with pytest.raises(OutputExistsError):
        save_ase(r.mesh, p)
    save_ase(r.mesh, p, force=True)


def test_cli_frep_demo_writes_mesh_and_report(tmp_path, capsys):
    out, rep = tmp_path / "torus.ply", tmp_path / "r.json"
    assert main(["frep", "--demo", "torus", "-o", str(out), "--qlev", "5", "--report", str(rep)]) == 0
    assert "watertight True" in capsys.readouterr().out
    v, f = load_raw(out)
    d = json.loads(rep.read_text())
    assert d["metrics"]["faces"] == len(f) and d["metrics"]["topology"]["genus"] == 1
    assert d["params"]["qlev"] == 5 and d["holes"] > 0 and "total" in d["timings"]
    # no silent overwrite
    assert main(["frep", "--demo", "torus", "-o", str(out), "--qlev", "5"]) == 2
    assert "exists" in capsys.readouterr().err
    assert main(["frep", "--demo", "torus", "-o", str(out), "--qlev", "4", "--force"]) == 0


def test_cli_frep_spec_file_to_ase_and_errors(tmp_path, capsys):
    spec = tmp_path / "s.json"
    spec.write_text(json.dumps({"name": "ell", "F": "1 - (x/0.7)**2 - (y/0.5)**2 - (z/0.4)**2"}))
    out = tmp_path / "e.ase"
    assert main(["frep", str(spec), "-o", str(out), "--qlev", "4"]) == 0
    v, f, _ = parse_ase(out.read_text())
    assert len(f) > 100
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"F": "open('x')"}))
    assert main(["frep", str(bad), "-o", str(tmp_path / "b.ply")]) == 2
    assert "unknown function" in capsys.readouterr().err
    assert main(["frep", "--demo", "nope", "-o", str(tmp_path / "c.ply")]) == 2
    assert main(["frep", "--demo", "torus", "-o", str(tmp_path / "c.xyz")]) == 2


def test_spec_loading_errors(tmp_path):
    p = tmp_path / "x.json"
    p.write_text("{not json")
    with pytest.raises(InputError):
        load_spec(p)
    p.write_text(json.dumps({"F": "x", "colour": 1}))
    with pytest.raises(InputError, match="unknown keys"):
        load_spec(p)
    p.write_text(json.dumps({"F": "x", "bounds": [[0, 0, 0], [0, 1, 1]]}))
    with pytest.raises(InputError, match="bounds"):
        load_spec(p)


def test_cli_frep_empty_object_is_an_error(tmp_path, capsys):
    spec = tmp_path / "e.json"
    spec.write_text(json.dumps({"F": "-1 - x**2"}))
    assert main(["frep", str(spec), "-o", str(tmp_path / "e.ply"), "--qlev", "3"]) == 2
    assert "no surface" in capsys.readouterr().err
    assert not (tmp_path / "e.ply").exists()
