import json
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import data_file

from algorithms.cli import main

ROOT = Path(__file__).resolve().parents[1]


def test_demos_lists_the_repair_demos(capsys):
    assert main(["demos"]) == 0
    out = capsys.readouterr().out
    for name in ("two-caps", "big-hole", "cut-torus", "two-holes"):
        assert name in out


def test_info_cut_torus(capsys):
    assert main(["info", "--demo", "cut-torus", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert len(d["islands"]) == 1 and len(d["loops"]) == 2


def test_info_two_caps_counts_free_points(capsys):
    assert main(["info", "--demo", "two-caps", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["class"] == "ICM3" and d["free_points"]["unreferenced"] == 40


def test_info_bunny(capsys):
    assert main(["info", str(data_file("bunny.ply")), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    main_island = d["islands"][0]
    assert len(main_island["loops"]) == 5
    assert d["free_points"]["unreferenced"] == 25
    reasons = {x["reason"].split(" of face")[0] for x in d["set_aside"]["faces"]}
    assert "duplicate" in reasons
    assert d["set_aside"]["count"] == len(d["set_aside"]["faces"]) > 80


@pytest.mark.parametrize("argv,msg", [
    (["info", "nope.ply"], "no such file"),
    (["info", "--demo", "nope"], "unknown demo"),
    (["info"], "no input"),
])
def test_errors_are_one_line_exit_2(capsys, argv, msg):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert msg in err and "\n" not in err and "Traceback" not in err


def test_a_file_of_degenerate_faces_is_an_error_and_writes_nothing(tmp_path, capsys):
    """Every face set aside (a zero-area triangle: three collinear vertices): normalisation keeps
    none (it used to fail inside the fan splitting with an IndexError), and the repair says why
    instead of writing an empty mesh as a "closed" surface."""
    bad = tmp_path / "flat.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n")
    out = tmp_path / "out.ply"
    assert main(["info", str(bad)]) == 0
    assert "degenerate: zero area" in capsys.readouterr().out
    assert main(["repair", str(bad), "-o", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert "no face to repair" in err and "1 degenerate: zero area" in err and "\n" not in err
    assert not out.exists()


def test_corrupt_file_through_the_real_command(tmp_path):
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n")
    r = subprocess.run([sys.executable, "-m", "viewer.cli", "info", str(bad)], cwd=ROOT,
                       capture_output=True, text=True)
    assert r.returncode == 2
    assert r.stderr.count("\n") == 1 and "NaN" in r.stderr and "Traceback" not in r.stderr
