"""`bridgefield shot` and the no-display fallback of `bridgefield`: the explorer's scene off screen,
checked by its pixels (the bridge colour map is present, the scene is not blank)."""

from __future__ import annotations

import numpy as np
import pytest

from viewer.cli import main

pytestmark = pytest.mark.gui


def viridis_pixels(img, tol=18) -> int:
    """Pixels close to the middle of viridis (the bridge quality colours; not the islands' pastels)."""
    import matplotlib

    c = np.array(matplotlib.colormaps["viridis"](np.linspace(0.1, 0.9, 9))[:, :3] * 255)
    px = img[..., :3].reshape(-1, 3).astype(float)
    return int((np.min(np.linalg.norm(px[:, None, :] - c[None], axis=2), axis=1) < tol).sum())


def not_blank(img) -> float:
    """Share of pixels that differ from the background gradient (per row: the row's median)."""
    rgb = np.asarray(img[..., :3], dtype=np.int32)
    return float((np.abs(rgb - np.median(rgb, axis=1, keepdims=True)).sum(axis=2) > 40).mean())


def test_shot_draws_the_bridges_by_quality(tmp_path, capsys):
    import imageio.v2 as imageio

    out = tmp_path / "two-caps.png"
    assert main(["shot", "--demo", "two-caps", "--size", "640x480", "-o", str(out)]) == 0
    assert "64 force lines" in capsys.readouterr().out
    img = imageio.imread(out)
    assert img.shape[:2] == (480, 640)
    assert not_blank(img) > 0.1
    with_bridges = viridis_pixels(img)
    assert with_bridges > 300  # the tubes and the scalar bar
    # the input alone has none of those colours: the bridges made them
    bare = tmp_path / "bare.png"
    assert main(["shot", "--demo", "two-caps", "--no-bridges", "--size", "640x480", "-o", str(bare)]) == 0
    assert viridis_pixels(imageio.imread(bare)) < with_bridges / 10
    # an existing image is never overwritten without --force
    before = out.read_bytes()
    assert main(["shot", "--demo", "two-caps", "-o", str(out)]) != 0
    assert "exists already" in capsys.readouterr().err
    assert out.read_bytes() == before


def test_shot_repair_draws_patches(tmp_path):
    import imageio.v2 as imageio

    out = tmp_path / "r.png"
    assert main(["shot", "--demo", "cut-torus", "--repair", "--size", "480x360", "-o", str(out)]) == 0
    img = imageio.imread(out)[..., :3].astype(int)
    patch = np.array([0x4e, 0x9b, 0xd1])  # PATCH_COLOUR, shaded
    blueish = (img[..., 2] > img[..., 0] + 40) & (np.abs(img - patch).sum(axis=2) < 150)
    assert blueish.mean() > 0.005


def test_no_display_writes_an_offscreen_png(tmp_path, monkeypatch, capsys):
    import imageio.v2 as imageio

    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert main([]) == 0
    err = capsys.readouterr().err
    assert "no display" in err and "bridgefield-demo.png" in err
    img = imageio.imread(tmp_path / "bridgefield-demo.png")
    assert viridis_pixels(img) > 300
    assert main([]) == 0  # a second run never overwrites: a new name
    assert (tmp_path / "bridgefield-demo-1.png").exists()
