"""load_photo and save_photo: a photo read as `brume render` reads it (upright, decoded by
its colour profile's curves) and written as it writes one (the profile and the EXIF
carried, atomically). Expected values come from the formulas (a pure gamma of 563/256,
the sRGB curve) and from Pillow's reading of the files, not from brume."""

import subprocess

import numpy as np
import pytest

import brume
from shared import REPO, brume_bin

Image = pytest.importorskip("PIL.Image")

COLOUR = REPO / "tests/data/colour"
GAMMA = 563 / 256  # the fixture profile's curve (tests/data/colour/README.md)


def linear_to_srgb(v):
    v = np.clip(np.asarray(v, dtype=np.float64), 0.0, 1.0)
    return np.where(v <= 0.0031308, v * 12.92, 1.055 * v ** (1 / 2.4) - 0.055)


def ramp_codes():
    i = np.arange(256)
    return np.stack([i, 255 - i, (7 * i) % 256], axis=1).reshape(16, 16, 3)


def test_a_photo_is_decoded_by_its_profiles_own_curve():
    linear, info = brume.load_photo(COLOUR / "gamma22-ramp.png", dtype="float32")
    assert linear.dtype == np.float32 and linear.shape == (16, 16, 3)
    np.testing.assert_allclose(linear, (ramp_codes() / 255.0) ** GAMMA, atol=2e-5)
    assert info["colour_profile"] == "Adobe RGB (1998) test"
    assert isinstance(info["icc_profile"], bytes) and info["exif"] is None
    assert info["orientation"] == 1
    # uint8: the same light encoded by the sRGB curve, as brume.fog takes it.
    codes, _ = brume.load_photo(COLOUR / "gamma22-ramp.png")
    assert codes.dtype == np.uint8
    want = np.round(linear_to_srgb((ramp_codes() / 255.0) ** GAMMA) * 255)
    assert np.abs(codes.astype(int) - want).max() <= 1
    # Pillow's codes, which brume.fog would take as sRGB's, mean other light (9 codes
    # apart at most, in the shadows).
    pillow = np.asarray(Image.open(COLOUR / "gamma22-ramp.png").convert("RGB"), int)
    assert np.abs(pillow - codes.astype(int)).max() > 5
    # A PNG whose gAMA says linear light.
    linear, info = brume.load_photo(COLOUR / "gama-linear-ramp.png", dtype="float32")
    np.testing.assert_allclose(linear, ramp_codes() / 255.0, atol=2e-5)
    assert info["colour_profile"] == "PNG gAMA 1.00000"


def test_a_tiff_photo_reads_as_pillow_turns_it_with_its_profile():
    """The LZW TIFF of the ramp with its profile and Orientation 6: upright as Pillow turns
    it, each code decoded by the profile's curve; its tags are not carried as EXIF."""
    linear, info = brume.load_photo(COLOUR / "gamma22-ramp.tif", dtype="float32")
    pillow = np.asarray(Image.open(COLOUR / "gamma22-ramp.tif").convert("RGB"), float)
    np.testing.assert_allclose(linear, (pillow / 255.0) ** GAMMA, atol=2e-5)
    assert info["colour_profile"] == "Adobe RGB (1998) test"
    assert info["orientation"] == 6 and info["exif"] is None


def test_python_fogs_a_profiled_photo_as_brume_render_does(tmp_path):
    """The Adobe RGB patch fogged through load_photo, fog and save_photo: the codes of
    `brume render` within 1, and the same profile."""
    np.save(tmp_path / "r.npy", np.full((8, 32), 10.0, np.float32))
    cmd = [
        str(brume_bin()), "render", "--image", str(COLOUR / "gamma22-flat.png"),
        "--depth", str(tmp_path / "r.npy"), "--depth-kind", "range", "--depth-scale", "1",
        "--beta", "0.1", "--airlight", "0.5,0.5,0.5", "--out", str(tmp_path / "cli.png"),
    ]  # fmt: skip
    subprocess.run(cmd, check=True, capture_output=True)
    image, info = brume.load_photo(COLOUR / "gamma22-flat.png")
    range_m = np.full((8, 32), 10.0, np.float32)
    foggy = brume.fog(image, range_m, beta=0.1, airlight=0.5)
    brume.save_photo(tmp_path / "py.png", foggy, info)
    cli, py = Image.open(tmp_path / "cli.png"), Image.open(tmp_path / "py.png")
    assert np.abs(np.asarray(cli, int) - np.asarray(py, int)).max() <= 1
    assert py.info["icc_profile"] == cli.info["icc_profile"] == info["icc_profile"]


def test_a_turned_photo_comes_upright_and_keeps_its_exif(tmp_path):
    image, info = brume.load_photo(REPO / "tests/data/exif/rot6.jpg")
    assert image.shape == (24, 16, 3)  # stored 24 x 16, Orientation 6
    assert info["orientation"] == 6 and isinstance(info["exif"], bytes)
    brume.save_photo(tmp_path / "out.jpg", image, info)
    exif = Image.open(tmp_path / "out.jpg").getexif()
    assert exif[0x0112] == 1  # upright now
    assert exif[0x010F] == "brume test" and exif[0x0110] == "fixture"


def test_save_photo_writes_whole_files_or_none(tmp_path):
    rng = np.random.default_rng(3)
    codes = rng.integers(0, 256, (6, 9, 3), dtype=np.uint8)
    brume.save_photo(tmp_path / "a.png", codes)
    assert np.array_equal(np.asarray(Image.open(tmp_path / "a.png")), codes)
    assert "icc_profile" not in Image.open(tmp_path / "a.png").info
    with pytest.raises(ValueError, match="invalid path = .*out.bmp"):
        brume.save_photo(tmp_path / "out.bmp", codes)
    with pytest.raises(OSError, match="its folder .*nope does not exist"):
        brume.save_photo(tmp_path / "nope" / "c.png", codes)
    with pytest.raises(ValueError, match="exif"):
        brume.save_photo(tmp_path / "b.png", codes, {"exif": "not bytes"})
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.png"]
    with pytest.raises(ValueError, match="dtype"):
        brume.load_photo(tmp_path / "a.png", dtype="int8")
    with pytest.raises(OSError, match="missing.png"):
        brume.load_photo(tmp_path / "missing.png")


def test_aerial_is_integrated_for_the_photos_primaries(tmp_path):
    """brume.aerial given load_photo's icc_profile equals `brume render --medium aerial`
    of the Display P3 photo within 1/255, which integrates the attenuation for P3's
    primaries; without the profile (sRGB's primaries) the blue differs."""
    range_m = np.full((8, 32), 5000.0, np.float32)
    np.save(tmp_path / "r.npy", range_m)
    cmd = [
        str(brume_bin()), "render", "--image", str(COLOUR / "p3-flat.png"),
        "--depth", str(tmp_path / "r.npy"), "--depth-kind", "range", "--depth-scale", "1",
        "--medium", "aerial", "--turbidity", "2", "--fov", "50",
        "--airlight", "0.9,0.9,0.9", "--out", str(tmp_path / "cli.png"),
    ]  # fmt: skip
    subprocess.run(cmd, check=True, capture_output=True)
    cli = np.asarray(Image.open(tmp_path / "cli.png"), int)
    image, info = brume.load_photo(COLOUR / "p3-flat.png")
    keywords = dict(turbidity=2.0, fov_y_deg=50.0, airlight=0.9)
    p3 = brume.aerial(image, range_m, icc_profile=info["icc_profile"], **keywords)
    assert np.abs(p3.astype(int) - cli).max() <= 1
    srgb = brume.aerial(image, range_m, **keywords)
    assert np.abs(srgb.astype(int) - cli)[..., 2].max() >= 2
