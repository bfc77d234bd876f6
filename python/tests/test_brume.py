"""Tests of the Python package: shapes and dtypes, the physics checked in numpy, the
errors, the augmentation's seeding, and equality with the `brume render` program."""

import json
import math
import os
import subprocess
import warnings

import numpy as np
import pytest

import brume
from shared import REPO, assert_threads_match_serial, brume_bin, sky_over_ground

H, W = 48, 64  # small: llvmpipe on 2 cores


def brume_render(tmp_path, image_u8, range_m, flags):
    """`brume render` of the image (PNG) and the range (a float .npy in metres:
    `--depth-kind range --depth-scale 1`) with `flags`; its output as uint8 RGB."""
    Image = pytest.importorskip("PIL.Image")
    Image.fromarray(image_u8).save(tmp_path / "image.png")
    np.save(tmp_path / "range.npy", range_m.astype(np.float32))
    cmd = [
        str(brume_bin()), "render",
        "--image", str(tmp_path / "image.png"),
        "--depth", str(tmp_path / "range.npy"),
        "--depth-kind", "range", "--depth-scale", "1",
        "--out", str(tmp_path / "cli.png"), *flags,
    ]  # fmt: skip
    subprocess.run(cmd, check=True, capture_output=True)
    return np.asarray(Image.open(tmp_path / "cli.png").convert("RGB"))


def srgb_to_linear(c):
    c = np.asarray(c, dtype=np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def linear_to_srgb(v):
    v = np.clip(np.asarray(v, dtype=np.float64), 0.0, 1.0)
    return np.where(v <= 0.0031308, v * 12.92, 1.055 * v ** (1 / 2.4) - 0.055)


@pytest.fixture(scope="module")
def image_u8():
    rng = np.random.default_rng(7)
    # A smooth picture with some texture: no sky-like flat bright region.
    y, x = np.mgrid[0:H, 0:W]
    base = np.stack([x / W, y / H, 0.5 + 0.3 * np.sin(x / 5.0)], axis=-1)
    noise = rng.random((H, W, 3)) * 0.2
    return np.clip((base * 0.7 + noise) * 255, 0, 255).astype(np.uint8)


@pytest.fixture(scope="module")
def range_m():
    # 5 m at the left to 120 m at the right, a little slope down the rows.
    y, x = np.mgrid[0:H, 0:W].astype(np.float32)
    return (5.0 + 115.0 * x / (W - 1) + 0.5 * y).astype(np.float32)


def test_the_build_is_named():
    """__sources__ tells two builds of one __version__ apart: 16 hex digits."""
    assert isinstance(brume.__version__, str) and brume.__version__
    assert len(brume.__sources__) == 16
    int(brume.__sources__, 16)


def test_shapes_and_dtypes(image_u8, range_m):
    out = brume.fog(image_u8, range_m, beta=0.02)
    assert out.shape == image_u8.shape and out.dtype == np.uint8
    linear = srgb_to_linear(image_u8 / 255.0).astype(np.float32)
    out32 = brume.fog(linear, range_m, beta=0.02)
    assert out32.shape == image_u8.shape and out32.dtype == np.float32
    out64 = brume.fog(linear.astype(np.float64), range_m.astype(np.float64), beta=0.02)
    assert out64.dtype == np.float64
    np.testing.assert_allclose(out64, out32, atol=1e-6)
    # float16, a half-precision pipeline's: read exactly as float32 of its values, and
    # the result rounded to float16 as numpy rounds (to nearest, ties to even).
    linear16 = linear.astype(np.float16)
    out16 = brume.fog(linear16, range_m, beta=0.02)
    assert out16.shape == image_u8.shape and out16.dtype == np.float16
    np.testing.assert_array_equal(
        out16, brume.fog(linear16.astype(np.float32), range_m, beta=0.02).astype(np.float16)
    )
    # A non-contiguous view is read as the array it shows.
    flipped = np.ascontiguousarray(image_u8[:, ::-1])
    np.testing.assert_array_equal(
        brume.fog(image_u8[:, ::-1], range_m, beta=0.02, blur=False, airlight=(0.8, 0.8, 0.8)),
        brume.fog(flipped, range_m, beta=0.02, blur=False, airlight=(0.8, 0.8, 0.8)),
    )


def test_a_range_with_a_channel_axis_of_one(image_u8, range_m):
    # HxWx1 (numpy's, albumentations' masks) and 1xHxW (a torch depth tensor's .numpy()):
    # the same range as HxW, here and as RandomFog's depth.
    want = brume.fog(image_u8, range_m, beta=0.02, refine="none")
    for shaped in (range_m[..., None], range_m[None]):
        np.testing.assert_array_equal(brume.fog(image_u8, shaped, beta=0.02, refine="none"), want)
    t = brume.augment.RandomFog(beta_range=(0.02, 0.02), refine="none", seed=1)
    np.testing.assert_array_equal(t(image=image_u8, depth=range_m[..., None])["image"], want)


def test_smaller_range_is_upsampled(image_u8, range_m):
    out = brume.fog(image_u8, range_m[::2, ::2].copy(), beta=0.02, refine=False)
    assert out.shape == image_u8.shape


def test_beta_and_visibility_agree(image_u8, range_m):
    linear = srgb_to_linear(image_u8 / 255.0).astype(np.float32)
    beta = 0.013
    a = brume.fog(linear, range_m, beta=beta)
    b = brume.fog(linear, range_m, visibility=-math.log(0.05) / beta)
    np.testing.assert_allclose(a, b, atol=1e-5)


def test_a_sequence_of_betas_gives_one_output_each(image_u8, range_m):
    """beta=[...] (or visibility=[...]) returns a list, each output the call with that
    value alone (the capture's noise and return_info's labels included)."""
    betas = (0.005, 0.01, 0.02)
    kw = dict(read_noise=0.01, seed=7, return_info=True)
    many = brume.fog(image_u8, range_m, beta=list(betas), **kw)
    assert isinstance(many, list) and len(many) == 3
    for beta, (image, info) in zip(betas, many):
        alone, alone_info = brume.fog(image_u8, range_m, beta=beta, **kw)
        np.testing.assert_array_equal(image, alone)
        np.testing.assert_array_equal(info["transmittance"], alone_info["transmittance"])
        assert info["beta"] == beta and info["airlight"] == alone_info["airlight"]
    visibilities = np.array([100.0, 300.0])
    images = brume.Renderer().fog(image_u8, range_m, visibility=visibilities)
    assert len(images) == 2 and images[0].mean() > images[1].mean()
    np.testing.assert_array_equal(images[1], brume.fog(image_u8, range_m, visibility=300.0))
    # A one-element sequence is still a list, a numpy one too (which numpy 2.2, on Python
    # 3.10, would also convert to a number, warning); a single number is not, nor a 0-d
    # array.
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for one in ([0.01], np.array([0.01])):
            assert isinstance(brume.fog(image_u8, range_m, beta=one), list)
        for number in (0.01, np.float32(0.01), np.array(0.01)):
            assert isinstance(brume.fog(image_u8, range_m, beta=number), np.ndarray)
    assert not caught, [str(w.message) for w in caught]
    # Every output of a list is held until the call returns: too many is refused first.
    with pytest.raises(MemoryError, match="2000000 outputs of 3072 px each needs about"):
        brume.fog(image_u8, range_m, beta=[0.01] * 2_000_000)
    # A string from a config file is named by its value, on every Python version.
    with pytest.raises(TypeError, match="'0.02' is not a number: expected a number, or a"):
        brume.fog(image_u8, range_m, beta="0.02")


def test_koschmieder_computed_in_numpy(image_u8, range_m):
    """blur=False, given airlight: I = tau J + (1 - tau) A with tau = exp(-beta R)."""
    linear = srgb_to_linear(image_u8 / 255.0).astype(np.float32)
    airlight = np.array([0.7, 0.75, 0.8])
    beta = 0.02
    out = brume.fog(linear, range_m, beta=beta, airlight=airlight, blur=False, refine=False)
    tau = np.exp(-beta * range_m.astype(np.float64))[..., None]
    expected = tau * linear + (1.0 - tau) * airlight
    assert np.abs(out - expected).max() < 1e-4


def test_one_airlight_value_is_a_grey(image_u8, range_m):
    """airlight=0.7 (RESIDE's scalar A) is the grey (0.7, 0.7, 0.7); a bool is no colour."""
    kw = dict(beta=0.02, blur=False, refine=False)
    grey = brume.fog(image_u8, range_m, airlight=0.7, **kw)
    np.testing.assert_array_equal(grey, brume.fog(image_u8, range_m, airlight=(0.7,) * 3, **kw))
    np.testing.assert_array_equal(
        grey, brume.fog(image_u8, range_m, airlight=np.float32(0.7), **kw)
    )
    for bad in (True, "grey", [[0.7, 0.7, 0.7]]):
        with pytest.raises(TypeError, match="is not a colour: expected a number"):
            brume.fog(image_u8, range_m, airlight=bad, **kw)


def test_info_gives_the_labels_the_render_used(image_u8, range_m):
    """return_info: t = exp(-beta R) of the range the fog read, and the image obeys
    I = J t + A (1 - t) with that t and the reported A (no blur), computed in numpy."""
    linear = srgb_to_linear(image_u8 / 255.0).astype(np.float32)
    holed = range_m.copy()
    holed[10:14, 20:26] = np.nan  # a hole, which pre-processing fills
    out, info = brume.fog(linear, holed, beta=0.02, blur=False, refine=False, return_info=True)
    assert set(info) == {
        "transmittance", "range_m", "airlight", "airlight_source", "beta", "visibility_m",
        "sigma_max_px",
    }  # fmt: skip
    t, r = info["transmittance"], info["range_m"]
    assert t.shape == r.shape == (H, W) and t.dtype == r.dtype == np.float32
    assert np.isfinite(r).all() and (r[10:14, 20:26] > 0).all()
    known = np.isfinite(holed)
    np.testing.assert_allclose(r[known], holed[known], rtol=1e-6)
    np.testing.assert_allclose(t, np.exp(-0.02 * r.astype(np.float64)), rtol=1e-6, atol=1e-7)
    assert info["beta"] == 0.02 and abs(info["visibility_m"] - math.log(20) / 0.02) < 1e-9
    assert info["airlight_source"] in ("sky", "neutral")
    a = np.array(info["airlight"])
    assert a.shape == (3,) and (a > 0).all()
    expected = t[..., None] * linear + (1.0 - t[..., None]) * a
    assert np.abs(out - expected).max() < 1e-4
    # The same image as without return_info; the airlight given is the one reported.
    np.testing.assert_array_equal(
        out, brume.fog(linear, holed, beta=0.02, blur=False, refine=False)
    )
    _, given = brume.fog(image_u8, range_m, beta=0.01, airlight=(0.7, 0.75, 0.8), return_info=True)
    assert given["airlight_source"] == "given"
    np.testing.assert_allclose(given["airlight"], (0.7, 0.75, 0.8), rtol=1e-6)
    assert given["sigma_max_px"] > 1.0


def test_normalised_haze_computed_in_numpy(image_u8, range_m):
    """ka/ks: paper 000's haze on the range divided by its largest value, in any unit:
    t = exp(-(ka + ks) R / R_max), the same in km as in m."""
    linear = srgb_to_linear(image_u8 / 255.0).astype(np.float32)
    airlight = np.array([0.7, 0.75, 0.8])
    kw = dict(ka=0.5, ks=1.5, airlight=airlight, blur=False, refine=False, return_info=True)
    out, info = brume.fog(linear, range_m, **kw)
    r = range_m.astype(np.float64)
    tau = np.exp(-2.0 * r / r.max())
    np.testing.assert_allclose(info["transmittance"], tau, rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(info["range_m"], r, rtol=1e-6)
    assert abs(info["beta"] - 2.0 / r.max()) < 1e-9
    expected = tau[..., None] * linear + (1.0 - tau[..., None]) * airlight
    assert np.abs(out - expected).max() < 1e-4
    km, _ = brume.fog(linear, range_m / 1000.0, **kw)
    np.testing.assert_allclose(km, out, atol=1e-5)
    # Only ks: ka takes paper 000's 0.25; with blur, a larger lambda_px blurs more.
    only_ks = brume.fog(linear, range_m, ks=1.5, airlight=airlight, blur=False, refine=False)
    tau_ks = np.exp(-1.75 * r / r.max())[..., None]
    assert np.abs(only_ks - (tau_ks * linear + (1.0 - tau_ks) * airlight)).max() < 1e-4
    _, weak = brume.fog(linear, range_m, ks=1.5, lambda_px=2.0, return_info=True)
    _, strong = brume.fog(linear, range_m, ks=1.5, lambda_px=12.0, return_info=True)
    assert 1.0 < weak["sigma_max_px"] < strong["sigma_max_px"]


def test_sky_and_ego_masks(tmp_path, image_u8, range_m):
    """A sky mask replaces the detection (its colour the airlight, its range the farthest),
    an ego mask is never fogged; the same pixels as `brume render --sky-mask --ego-mask`."""
    sky = np.zeros((H, W), bool)
    sky[:10] = True
    ego = np.zeros((H, W), np.uint8)
    ego[-6:, 20:40] = 255
    linear = srgb_to_linear(image_u8 / 255.0).astype(np.float32)
    kw = dict(beta=0.02, blur=False, refine=False, return_info=True)
    out, info = brume.fog(linear, range_m, sky_mask=sky, ego_mask=ego, **kw)
    assert info["airlight_source"] == "sky"
    np.testing.assert_allclose(info["airlight"], np.median(linear[sky], axis=0), atol=0.02)
    # The sky's range is the farthest (but in the horizon's margin, where it is matted),
    # the hood's 0: transmittance 1 and its pixels as they were (no blur here).
    t = info["transmittance"]
    assert t[0].max() == t.min() < t[~sky].min()
    assert (info["range_m"][ego != 0] == 0).all() and (t[ego != 0] == 1).all()
    np.testing.assert_allclose(out[ego != 0], linear[ego != 0], atol=1e-6)
    # An integer mask is a bool one; the results equal the program's.
    np.testing.assert_array_equal(
        brume.fog(image_u8, range_m, beta=0.02, sky_mask=sky.astype(np.int64), ego_mask=ego),
        ours := brume.fog(image_u8, range_m, beta=0.02, sky_mask=sky, ego_mask=ego != 0),
    )
    Image = pytest.importorskip("PIL.Image")
    Image.fromarray(sky.astype(np.uint8) * 255).save(tmp_path / "sky.png")
    Image.fromarray(ego).save(tmp_path / "ego.png")
    flags = ["--beta", "0.02", "--refine", "repair"]
    flags += ["--sky-mask", str(tmp_path / "sky.png"), "--ego-mask", str(tmp_path / "ego.png")]
    cli = brume_render(tmp_path, image_u8, range_m, flags)
    assert np.abs(ours.astype(np.int32) - cli.astype(np.int32)).max() <= 1
    with pytest.raises(ValueError, match=r"sky_mask: .*shape 48x64, got shape \[24, 32\]"):
        brume.fog(image_u8, range_m, beta=0.02, sky_mask=sky[::2, ::2])
    with pytest.raises(ValueError, match="sky_mask: every pixel is set"):
        brume.fog(image_u8, range_m, beta=0.02, sky_mask=np.ones((H, W), bool))
    with pytest.raises(ValueError, match="ego_mask: .*got dtype float32"):
        brume.fog(image_u8, range_m, beta=0.02, ego_mask=np.zeros((H, W), np.float32))


def test_info_transmittance_at_the_image_size(image_u8, range_m):
    small = range_m[::2, ::2].copy()
    out, info = brume.fog(image_u8, small, visibility=300.0, return_info=True)
    assert info["transmittance"].shape == info["range_m"].shape == image_u8.shape[:2]
    np.testing.assert_allclose(
        info["transmittance"],
        np.exp(-info["beta"] * info["range_m"].astype(np.float64)),
        rtol=1e-6,
        atol=1e-7,
    )
    r = brume.Renderer()
    out_r, info_r = r.fog(image_u8, small, visibility=300.0, return_info=True)
    np.testing.assert_array_equal(out_r, out)
    np.testing.assert_array_equal(info_r["transmittance"], info["transmittance"])


def test_uint8_is_the_float_path_encoded(image_u8, range_m):
    linear = srgb_to_linear(image_u8 / 255.0).astype(np.float32)
    kw = dict(beta=0.02, airlight=(0.7, 0.75, 0.8), blur=False, refine=False)
    out8 = brume.fog(image_u8, range_m, **kw)
    out32 = brume.fog(linear, range_m, **kw)
    expected = np.round(linear_to_srgb(out32) * 255.0)
    assert np.abs(out8.astype(np.int32) - expected).max() <= 1
    # Far pixels move toward the airlight (its sRGB code values 218-231).
    far = range_m > 100
    assert out8[far].mean() > image_u8[far].mean()


def test_uint16_is_the_float_path_encoded_and_what_render_reads(tmp_path, image_u8, range_m):
    # 16-bit sRGB code values that 8 bits cannot hold: a smooth ramp plus fine steps.
    y, x = np.mgrid[0:H, 0:W]
    ramp = np.stack([x / W, y / H, (x + y) / (W + H)], axis=-1)
    image16 = np.round(ramp * 60000 + (x % 7)[..., None] * 13).astype(np.uint16)
    linear = srgb_to_linear(image16 / 65535.0).astype(np.float32)
    kw = dict(beta=0.02, airlight=(0.7, 0.75, 0.8), blur=False, refine=False)
    out16 = brume.fog(image16, range_m, **kw)
    assert out16.dtype == np.uint16 and out16.shape == image16.shape
    out32 = brume.fog(linear, range_m, **kw)
    expected = np.round(linear_to_srgb(out32) * 65535.0)
    assert np.abs(out16.astype(np.int64) - expected).max() <= 1
    far = range_m > 100
    assert out16[far].mean() > image16[far].mean()

    # `brume render` reads a 16-bit PNG the same way (and writes 8 bits).
    cv2 = pytest.importorskip("cv2")
    cv2.imwrite(str(tmp_path / "image16.png"), image16[..., ::-1])
    np.save(tmp_path / "range.npy", range_m.astype(np.float32))
    cmd = [
        str(brume_bin()), "render",
        "--image", str(tmp_path / "image16.png"),
        "--depth", str(tmp_path / "range.npy"),
        "--depth-kind", "range", "--depth-scale", "1", "--no-prep",
        "--beta", "0.02", "--airlight", "0.7,0.75,0.8", "--lambda", "0",
        "--out", str(tmp_path / "cli.png"),
    ]  # fmt: skip
    subprocess.run(cmd, check=True, capture_output=True)
    cli = cv2.imread(str(tmp_path / "cli.png"))[..., ::-1]
    assert np.abs(out16 / 257.0 - cli).max() <= 1.0


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(), "neither beta, visibility nor ka/ks"),
        (dict(beta=0.01, visibility=300.0), "expected exactly one"),
        (dict(visibility=300.0, ks=1.0), "visibility and ka/ks given together"),
        (dict(ka=-1.0), "ka"),
        (dict(ks=float("inf")), "ks"),
        (dict(beta=0.01, blur=False, lambda_px=4.0), "lambda_px only with blur"),
        (dict(beta=0.01, lambda_px=-1.0), "invalid lambda_px"),
        (dict(beta=-1.0), "invalid beta"),
        (dict(beta=float("nan")), "invalid beta"),
        (dict(visibility=0.0), "invalid visibility"),
        (dict(beta=0.01, refine="sometimes"), "invalid refine"),
        (dict(beta=0.01, refine=3), "invalid refine"),
        (dict(beta=0.01, airlight=(1.0, 1.0)), "invalid airlight"),
        (dict(beta=0.01, airlight=(-1.0, 1.0, 1.0)), "airlight"),
        (dict(beta=[]), r"invalid beta = \[\]: expected a number, or a non-empty sequence"),
        (dict(beta=[0.01, -1.0]), "invalid beta = -1"),
        (dict(visibility=[100.0, 0.0]), "invalid visibility = 0"),
    ],
)
def test_bad_options(image_u8, range_m, kwargs, message):
    with pytest.raises(ValueError, match=message):
        brume.fog(image_u8, range_m, **kwargs)


def test_float_code_values_are_warned_about(image_u8, range_m):
    """image.astype(np.float32) (code values as floats) warns; linear light, HDR above 1
    and uint8 do not."""
    with pytest.warns(UserWarning, match=f"up to {image_u8.max()} looks like 8-bit code values"):
        brume.fog(image_u8.astype(np.float32), range_m, beta=0.02)
    linear = srgb_to_linear(image_u8 / 255.0).astype(np.float32)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for image in (image_u8, linear, linear * 40.0):
            brume.fog(image, range_m, beta=0.02)


def test_bad_arrays(image_u8, range_m):
    with pytest.raises(ValueError, match="shape HxWx3"):
        brume.fog(image_u8[..., :2], range_m, beta=0.01)
    # The usual mistakes get their fix: channels first (torch's layout), RGBA, grey.
    with pytest.raises(ValueError, match=r"channels first.*transpose\(1, 2, 0\)"):
        brume.fog(np.ascontiguousarray(image_u8.transpose(2, 0, 1)), range_m, beta=0.01)
    with pytest.raises(ValueError, match=r"RGBA: image\[\.\.\., :3\]"):
        brume.fog(np.dstack([image_u8, image_u8[..., :1]]), range_m, beta=0.01)
    with pytest.raises(ValueError, match="grey"):
        brume.fog(image_u8[..., 0], range_m, beta=0.01)
    with pytest.raises(ValueError, match="dtype uint8.*float32, float64 or float16"):
        brume.fog(image_u8.astype(np.int16), range_m, beta=0.01)
    with pytest.raises(ValueError, match="numpy array"):
        brume.fog([[1, 2, 3]], range_m, beta=0.01)
    with pytest.raises(ValueError, match="shape HxW"):
        brume.fog(image_u8, np.dstack([range_m, range_m]), beta=0.01)
    with pytest.raises(ValueError, match="which axis is the height"):
        brume.fog(image_u8[:1], range_m[:1].reshape(1, -1, 1), beta=0.01)
    with pytest.raises(ValueError, match="dtype float32"):
        brume.fog(image_u8, range_m.astype(np.int32), beta=0.01)
    # Named by the arguments: range_m and the image.
    with pytest.raises(ValueError, match=r"invalid depth = range_m \(64x10\): expected a depth map for image"):
        brume.fog(image_u8, range_m[:10], beta=0.01)
    bad = srgb_to_linear(image_u8 / 255.0).astype(np.float32)
    bad[3, 5, 1] = np.nan
    with pytest.raises(ValueError, match=r"x 5, y 3\), channel 1"):
        brume.fog(bad, range_m, beta=0.01)
    # No pixel of known range: refused by the argument's name, whatever else is asked
    # (no pre-processing, no refinement); a range of 0 or less is unknown, and the
    # message says so.
    for unknown in [np.full((H, W), np.nan, np.float32), -range_m, 0 * range_m]:
        for kwargs in [dict(beta=0.01), dict(ka=0.2, ks=0.5, refine=False)]:
            with pytest.raises(ValueError, match=r"^range_m: no valid depth value \(every pixel unknown: NaN, infinite, zero or negative\)$"):
                brume.fog(image_u8, unknown, **kwargs)


def test_renderer_reused_from_threads(image_u8, range_m):
    renderer = brume.Renderer()
    assert "Renderer" in repr(renderer) and renderer.gl_renderer
    betas = [0.005, 0.01, 0.02, 0.03]
    serial = assert_threads_match_serial(
        [lambda b=b: renderer.fog(image_u8, range_m, beta=b) for b in betas]
    )
    np.testing.assert_array_equal(serial[2], brume.fog(image_u8, range_m, beta=0.02))


def test_random_fog_seeding(image_u8, range_m):
    a = brume.augment.RandomFog(beta_range=(0.005, 0.03), seed=3)
    b = brume.augment.RandomFog(beta_range=(0.005, 0.03), seed=3)
    outs_a = [a(image=image_u8, depth=range_m) for _ in range(3)]
    outs_b = [b(image=image_u8, depth=range_m) for _ in range(3)]
    for x, y in zip(outs_a, outs_b):
        assert x["beta"] == y["beta"] and 0.005 <= x["beta"] <= 0.03
        np.testing.assert_array_equal(x["image"], y["image"])
        assert x["depth"] is range_m
    assert len({o["beta"] for o in outs_a}) == 3
    c = brume.augment.RandomFog(seed=4)(image=image_u8, depth=range_m, mask="kept")
    assert c["beta"] != outs_a[0]["beta"] and c["mask"] == "kept"
    skipped = brume.augment.RandomFog(seed=3, p=0.0)(image=image_u8, depth=range_m)
    assert skipped["image"] is image_u8 and skipped["beta"] is None
    with pytest.raises(ValueError, match="beta_range"):
        brume.augment.RandomFog(beta_range=(0.03, 0.005))
    # return_info adds the labels and keeps the image and the betas of the same seed.
    labelled = brume.augment.RandomFog(beta_range=(0.005, 0.03), seed=3, return_info=True)
    first = labelled(image=image_u8, depth=range_m)
    assert first["beta"] == outs_a[0]["beta"]
    np.testing.assert_array_equal(first["image"], outs_a[0]["image"])
    assert first["transmittance"].shape == (H, W) and len(first["airlight"]) == 3
    assert first["transmittance"].min() < 0.5 < first["transmittance"].max() < 1.0
    clear = brume.augment.RandomFog(p=0.0, return_info=True)(image=image_u8, depth=range_m)
    assert (clear["transmittance"] == 1.0).all() and clear["airlight"] is None
    # sky_mask and ego_mask targets go to the fog too, and pass through.
    ego = np.zeros((H, W), bool)
    ego[-6:, 20:40] = True
    masked = brume.augment.RandomFog(seed=3, return_info=True)(
        image=image_u8, depth=range_m, ego_mask=ego
    )
    assert masked["ego_mask"] is ego and (masked["transmittance"][ego] == 1.0).all()
    assert (first["transmittance"][ego] < 1.0).all()


def test_random_fog_airlight_range(image_u8, range_m):
    """airlight_range draws a grey A on each call (reported by return_info) after β, and
    renders as brume.fog with that β and grey."""
    t = brume.augment.RandomFog(seed=3, airlight_range=(0.45, 1.0), return_info=True, blur=False)
    first_beta = brume.augment.RandomFog(seed=3)(image=image_u8, depth=range_m)["beta"]
    greys = []
    for k in range(3):
        out = t(image=image_u8, depth=range_m)
        assert k > 0 or out["beta"] == first_beta
        grey = out["airlight"][0]
        assert 0.45 <= grey <= 1.0 and out["airlight"] == (grey, grey, grey)
        expected = brume.fog(image_u8, range_m, beta=out["beta"], airlight=grey, blur=False)
        np.testing.assert_array_equal(out["image"], expected)
        greys.append(grey)
    assert len(set(greys)) == 3
    with pytest.raises(ValueError, match="both given"):
        brume.augment.RandomFog(airlight=0.8, airlight_range=(0.7, 1.0))
    # compat goes to brume.fog as it is.
    fc = brume.augment.RandomFog(seed=3, compat="foggy-cityscapes")(image=image_u8, depth=range_m)
    assert fc["beta"] == first_beta
    np.testing.assert_array_equal(
        fc["image"], brume.fog(image_u8, range_m, beta=first_beta, compat="foggy-cityscapes")
    )
    with pytest.raises(ValueError, match="invalid airlight_range"):
        brume.augment.RandomFog(airlight_range=(1.0, 0.7))


def test_load_depth(tmp_path, range_m):
    path = tmp_path / "range.npy"
    np.save(path, range_m)
    loaded, info = brume.load_depth(path, format="float", kind="range")
    assert loaded.dtype == np.float32 and loaded.shape == range_m.shape
    np.testing.assert_array_equal(loaded, range_m)
    assert info["format"] == "float" and info["kind"] == "range"
    assert info["metric"] is False and info["unknown_pixels"] == 0
    assert set(info) == {
        "format", "kind", "units", "metric", "notes", "unknown_pixels", "stereo_focal_baseline",
        "stereo_view", "disparity_px", "ground",
    }  # fmt: skip
    assert info["stereo_focal_baseline"] is None and info["ground"] is None
    assert info["stereo_view"] is None and info["disparity_px"] is None
    with pytest.raises(OSError, match="missing.npy"):
        brume.load_depth(tmp_path / "missing.npy")
    # A path as Python's file functions take it: str, os.PathLike or bytes.
    for given in (str(path), os.fsencode(path)):
        again, _ = brume.load_depth(given, format="float", kind="range")
        np.testing.assert_array_equal(again, range_m)
    with pytest.raises(TypeError, match="expected str, bytes or os.PathLike object, not int"):
        brume.load_depth(3)
    # The loaders' errors name the keywords, here `format` (the library's `depth_format`).
    with pytest.raises(ValueError, match="invalid format = jpeg"):
        brume.load_depth(path, format="jpeg")


def test_load_depth_of_numpy_archives_half_floats_and_millimetres(tmp_path, range_m):
    """What numpy writes for the tools people run: Depth Pro's `np.savez_compressed(path,
    depth=depth)` (float16 when the model runs in half precision), an archive of one
    unnamed array, and a depth camera's uint16 millimetres saved with np.save."""
    expected = range_m.astype(np.float16).astype(np.float32)
    np.savez_compressed(tmp_path / "pro.npz", depth=range_m.astype(np.float16), f_px=1234.0)
    np.savez(tmp_path / "one.npz", range_m.astype(np.float16))
    for name in ("pro.npz", "one.npz"):
        loaded, info = brume.load_depth(tmp_path / name, kind="range")
        assert info["format"] == "float"
        np.testing.assert_array_equal(loaded, expected)
    mm = np.round(range_m * 1000).astype(np.uint16)
    mm[0, :5] = 0  # no measurement
    np.save(tmp_path / "mm.npy", mm)
    loaded, info = brume.load_depth(tmp_path / "mm.npy", format="png16", scale=0.001, kind="range")
    assert info["metric"] is True and info["unknown_pixels"] == 5
    np.testing.assert_allclose(loaded[1:], mm[1:] / 1000.0, rtol=1e-6)
    assert np.isnan(loaded[0, :5]).all()
    # Depth Pro's prediction saved whole: its focal length turns depth into range.
    np.savez(tmp_path / "whole.npz", depth=range_m, focallength_px=np.float32(50.0))
    np.save(tmp_path / "depth.npy", range_m)
    whole, info = brume.load_depth(tmp_path / "whole.npz", kind="depth")
    given, _ = brume.load_depth(tmp_path / "depth.npy", kind="depth", focal_px=50.0)
    np.testing.assert_array_equal(whole, given)
    assert (whole >= range_m).all() and (whole > range_m).any()
    assert any("'focallength_px': 50.00 px" in n for n in info["notes"])
    np.savez(tmp_path / "two.npz", a=range_m, b=range_m)
    with pytest.raises(ValueError, match=r"holds 2 arrays \(a, b\) and none is named 'depth'"):
        brume.load_depth(tmp_path / "two.npz")


def test_load_depth_of_a_portrait_jpeg():
    """A phone's portrait JPEG (GDepth, written by ExifTool: tests/data/gdepth/): its own
    scale and measure, the plane it encodes to half a 16-bit code, and its far corner at
    Far (the last code: where the map stops) unknown."""
    loaded, info = brume.load_depth(REPO / "tests/data/gdepth/lin16.jpg")
    assert info["format"] == "gdepth" and info["kind"] == "range" and info["metric"]
    assert info["unknown_pixels"] == 1 and np.isnan(loaded[23, 31])
    y, x = np.mgrid[0:24, 0:32]
    plane = 1.5 + 0.25 * x + 0.5 * y
    known = ~np.isnan(loaded)
    np.testing.assert_allclose(loaded[known], plane[known], atol=19.25 / 65535)


def test_load_depth_of_an_iphone_portrait():
    """An iPhone's portrait JPEG (tests/data/apple/: its Multi-Picture index read back by
    ExifTool): the disparity image after a matte, 1/m over 0.2..1.0 in 255 codes, made
    range by its IntrinsicMatrix (fx 30 px on the 32 x 24 map, principal point 14.75,
    12.75); the background rows at code 0 unknown. Computed here in numpy from the plane
    the file encodes, to a code and a half of disparity."""
    loaded, info = brume.load_depth(REPO / "tests/data/apple/portrait.jpg")
    assert info["format"] == "apple-depth" and info["kind"] == "depth" and info["metric"]
    assert loaded.shape == (24, 32)
    assert np.isnan(loaded[:8]).all() and not np.isnan(loaded[8:]).any()
    y, x = np.mgrid[8:24, 0:32].astype(np.float64)
    z = 1.0 + 0.05 * x + 0.1 * (y - 8)
    ray = np.sqrt(1.0 + ((x - 14.75) / 30.0) ** 2 + ((y - 12.75) / 30.0) ** 2)
    depth = loaded[8:] / ray
    assert np.abs(1.0 / depth - 1.0 / z).max() <= 1.5 * 0.8 / 255 + 1e-6


def test_load_depth_with_its_photo_turns_and_uses_its_exif():
    """image=: the photo's EXIF (ExifTool wrote f26.jpg's: Orientation 6, a phone held
    upright, and FocalLengthIn35mmFormat 26) turns the map upright with it, as PIL's
    exif_transpose turns the photo, and its focal length turns depth into range:
    f = 26 mm · (the map's diagonal, 40 px) / 43.27 mm, the same as focal_px on the map
    as stored, turned clockwise."""
    from PIL import Image, ImageOps

    path = REPO / "tests/data/gdepth/f26.jpg"
    upright, info = brume.load_depth(path, image=path)
    photo = ImageOps.exif_transpose(Image.open(path))
    assert upright.shape == (32, 24) and photo.size == (48, 64)
    assert any("from the photo's EXIF: 26 mm" in n for n in info["notes"]), info["notes"]
    focal = 26 * 40 / np.hypot(36, 24)
    stored, _ = brume.load_depth(path, focal_px=focal)
    assert stored.shape == (24, 32)
    np.testing.assert_allclose(upright, np.rot90(stored, -1), rtol=1e-6)
    # Taken as upright already, the map is not turned, and says so.
    as_is, info = brume.load_depth(path, image=path, layout="upright")
    assert as_is.shape == (24, 32)
    assert any("taken as upright (layout upright)" in n for n in info["notes"]), info["notes"]
    with pytest.raises(ValueError, match="invalid layout = sideways"):
        brume.load_depth(path, image=path, layout="sideways")


def pixel_radius2(h, w, focal):
    """((x - cx)² + (y - cy)²) / f² at the pixel centres, the principal point at the
    image's centre."""
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    return ((x + 0.5 - w / 2) ** 2 + (y + 0.5 - h / 2) ** 2) / focal**2


def test_load_depth_geometry_keywords(tmp_path):
    """Every depth flag of `brume render` is a keyword, and the loaders' messages and notes
    name the keywords: a z-buffer (near, far, fov_y_deg) and a depth map (focal_px) give
    the range computed here in numpy."""
    h, w = 48, 64
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    eye = 2.0 + 0.5 * x + 0.1 * y  # eye depth (m) along the optical axis
    near, far, fov = 0.5, 200.0, 60.0
    # OpenGL: NDC z = (f + n)/(f - n) - 2fn/((f - n) Z), window depth (z + 1)/2.
    ndc = (far + near) / (far - near) - 2.0 * far * near / ((far - near) * eye)
    np.save(tmp_path / "z.npy", ((ndc + 1.0) / 2.0).astype(np.float32))
    focal = (h / 2) / np.tan(np.radians(fov / 2))
    expected = eye * np.sqrt(1.0 + pixel_radius2(h, w, focal))
    rng, info = brume.load_depth(
        tmp_path / "z.npy", kind="zbuffer", near=near, far=far, fov_y_deg=fov
    )
    np.testing.assert_allclose(rng, expected, rtol=1e-4)
    assert info["kind"] == "zbuffer"
    assert (info["units"], info["metric"]) == ("file units", False)
    # Planes given in centimetres, scale: metres per unit of near and far.
    rng_cm, info = brume.load_depth(
        tmp_path / "z.npy", kind="zbuffer", near=near * 100, far=far * 100, fov_y_deg=fov,
        scale=0.01,
    )
    np.testing.assert_allclose(rng_cm, expected, rtol=1e-4)
    assert (info["units"], info["metric"]) == ("m", True)
    # Bevy's reversed-Z buffer with an infinite far plane: window depth near/eye.
    np.save(tmp_path / "rz.npy", (near / eye).astype(np.float32))
    rng_rz, info = brume.load_depth(
        tmp_path / "rz.npy", kind="zbuffer", near=near, far=float("inf"), fov_y_deg=fov,
        reversed_z=True,
    )
    np.testing.assert_allclose(rng_rz, expected, rtol=1e-5)
    assert any("reversed-Z" in n for n in info["notes"])
    # A monocular estimator's inverse depth, its scale fitted: depth = scale/d.
    np.save(tmp_path / "inverse.npy", (2.0 / eye).astype(np.float32))
    rng_inv, info = brume.load_depth(
        tmp_path / "inverse.npy", kind="inverse", fov_y_deg=fov, scale=2.0
    )
    np.testing.assert_allclose(rng_inv, expected, rtol=1e-5)
    assert (info["kind"], info["metric"]) == ("inverse", True)
    with pytest.raises(ValueError, match="needs near, far and fov_y_deg") as error:
        brume.load_depth(tmp_path / "z.npy", kind="zbuffer", near=near)
    assert "--" not in str(error.value)
    # A depth map along the optical axis, with its focal length in pixels.
    np.save(tmp_path / "depth.npy", eye.astype(np.float32))
    rng, info = brume.load_depth(tmp_path / "depth.npy", kind="depth", focal_px=50.0)
    np.testing.assert_allclose(rng, eye * np.sqrt(1.0 + pixel_radius2(h, w, 50.0)), rtol=1e-5)
    with pytest.warns(UserWarning, match="focal_px ignored"):
        _, info = brume.load_depth(tmp_path / "depth.npy", kind="range", focal_px=50.0)
    assert any("focal_px ignored" in n for n in info["notes"]), info["notes"]
    # Clipping planes belong to a z-buffer only.
    with pytest.warns(UserWarning, match="near and far ignored"):
        _, info = brume.load_depth(
            tmp_path / "depth.npy", kind="depth", focal_px=50.0, near=0.5
        )
    assert any("near and far ignored" in n for n in info["notes"]), info["notes"]
    assert not any("--" in n for n in info["notes"]), info["notes"]


def test_range_from_depth(tmp_path):
    """An array in memory reads as load_depth reads a float file of it: each kind gives
    the range computed here in numpy, and equals load_depth of the same array as .npy."""
    h, w = 48, 64
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    eye = 2.0 + 0.5 * x + 0.1 * y  # eye depth (m) along the optical axis
    fov, focal, baseline_mm = 60.0, 50.0, 120.0
    ray_fov = np.sqrt(1.0 + pixel_radius2(h, w, (h / 2) / np.tan(np.radians(fov / 2))))
    ray_focal = np.sqrt(1.0 + pixel_radius2(h, w, focal))
    near, far = 0.5, 200.0
    ndc = (far + near) / (far - near) - 2.0 * far * near / ((far - near) * eye)
    cases = [
        (eye, dict(kind="depth", fov_y_deg=fov), eye * ray_fov, ("file units", False)),
        (eye * 100, dict(kind="depth", focal_px=focal, scale=0.01), eye * ray_focal, ("m", True)),
        (eye * ray_fov, dict(kind="range", scale=1.0), eye * ray_fov, ("m", True)),
        # Disparity d = f B / z with the offset taken off first: z = f B / (d + offset).
        (
            focal * baseline_mm / 1000 / eye - 3.0,
            dict(kind="disparity", focal_px=focal, baseline_mm=baseline_mm, disparity_offset_px=3.0),
            eye * ray_focal,
            ("m", True),
        ),
        # A monocular model's relative inverse depth with a shift: depth = 1/(d + offset).
        (1.0 / eye - 0.02, dict(kind="inverse", fov_y_deg=fov, disparity_offset_px=0.02),
         eye * ray_fov, ("relative units", False)),
        # Marigold's affine-invariant depth: depth = near + d·(far − near), the scene's
        # nearest and farthest depth given.
        ((eye - 1.5) / 38.5, dict(kind="affine", near=1.5, far=40.0, fov_y_deg=fov, scale=1.0),
         eye * ray_fov, ("m", True)),
        ((ndc + 1.0) / 2.0, dict(kind="zbuffer", near=near, far=far, fov_y_deg=fov),
         eye * ray_fov, ("file units", False)),
        (near / eye, dict(kind="zbuffer", near=near, far=float("inf"), fov_y_deg=fov,
                          reversed_z=True, scale=1.0), eye * ray_fov, ("m", True)),
    ]  # fmt: skip
    for values, keywords, expected, (units, metric) in cases:
        for dtype in (np.float32, np.float64):
            rng, info = brume.range_from_depth(values.astype(dtype), **keywords)
            assert rng.dtype == np.float32 and rng.shape == (h, w)
            np.testing.assert_allclose(rng, expected, rtol=2e-5, err_msg=str(keywords))
            assert (info["format"], info["kind"]) == ("float", keywords["kind"])
            assert (info["units"], info["metric"]) == (units, metric), keywords
        np.save(tmp_path / "map.npy", values.astype(np.float32))
        from_file, file_info = brume.load_depth(tmp_path / "map.npy", **keywords)
        np.testing.assert_array_equal(rng, from_file)
        disparity, file_disparity = info.pop("disparity_px"), file_info.pop("disparity_px")
        assert info == file_info
        if keywords["kind"] == "disparity":  # the array's values, as the file's
            np.testing.assert_array_equal(disparity, file_disparity)
            np.testing.assert_array_equal(disparity, values.astype(np.float32))
        else:
            assert disparity is None and file_disparity is None

    # Unknown values: NaN and infinite; the sky of inverse depth (d + offset <= 0).
    holes = eye.copy()
    holes[0, :3] = [np.nan, np.inf, -np.inf]
    rng, info = brume.range_from_depth(holes, kind="range")
    assert np.isnan(rng[0, :3]).all() and info["unknown_pixels"] == 3
    sky = 1.0 / eye
    sky[:5] = 0.0
    rng, info = brume.range_from_depth(sky, kind="inverse", fov_y_deg=fov)
    assert np.isnan(rng[:5]).all() and info["unknown_pixels"] == 5 * w
    # Depth Pro's sky, clamped at 10 km: unknown, as a NaN sky; with sky_beyond, the range
    # at or beyond it; float('inf') keeps every value.
    clamped = eye.copy()
    clamped[:5] = 10_000.0
    rng, info = brume.range_from_depth(clamped, kind="range")
    assert np.isnan(rng[:5]).all() and info["unknown_pixels"] == 5 * w
    assert any("a clamp" in n and "sky_beyond" in n for n in info["notes"]), info["notes"]
    rng, info = brume.range_from_depth(clamped, kind="range", sky_beyond=float("inf"))
    assert info["unknown_pixels"] == 0
    rng, info = brume.range_from_depth(eye, kind="range", sky_beyond=30.0)
    assert info["unknown_pixels"] == int((eye >= 30.0).sum()) > 0
    with pytest.raises(ValueError, match="invalid sky_beyond = 0"):
        brume.range_from_depth(eye, kind="range", sky_beyond=0.0)
    # A monocular model's sky at a small positive disparity: with monocular=True fog finds
    # it in the far tail, as the same range with the sky unknown; without, it is a surface.
    image, disparity = sky_over_ground(eye, 0.002 + 0.00002 * np.arange(w))
    rng, _ = brume.range_from_depth(disparity, kind="inverse", fov_y_deg=fov)
    unknown_sky = rng.copy()
    unknown_sky[:12] = np.nan
    want = brume.fog(image, unknown_sky, ks=0.75, refine="none")
    got = brume.fog(image, rng, ks=0.75, refine="none", monocular=True)
    assert np.abs(got.astype(int) - want.astype(int)).max() <= 1
    plain = brume.fog(image, rng, ks=0.75, refine="none")
    assert np.abs(plain.astype(int) - want.astype(int)).max() > 8
    # RandomFog and albumentations' Fog pass monocular on to the fog.
    from brume.albumentations import Fog as AlbumentationsFog

    metric, _ = brume.range_from_depth(disparity, kind="inverse", fov_y_deg=fov, scale=20.0)
    want = brume.fog(image, metric, beta=0.02, monocular=True)
    random_fog = brume.augment.RandomFog(beta_dist="0.02", seed=0, monocular=True)
    np.testing.assert_array_equal(random_fog(image=image, depth=metric)["image"], want)
    assert "monocular=True" in repr(random_fog)
    fog = AlbumentationsFog(beta_dist="0.02", monocular=True)
    np.testing.assert_array_equal(fog.apply(image, beta=0.02, depth=metric), want)
    assert "monocular" in fog.get_transform_init_args_names()
    assert not np.array_equal(brume.fog(image, metric, beta=0.02), want)
    # Affine depth's sky: the far plane, 1, where Marigold clamps it.
    marigold = (eye - 1.5) / 38.5
    marigold[:5] = 1.0
    rng, info = brume.range_from_depth(marigold, kind="affine", near=1.5, far=40.0, fov_y_deg=fov)
    assert np.isnan(rng[:5]).all() and info["unknown_pixels"] == 5 * w
    with pytest.raises(ValueError, match="invalid near = nothing") as error:
        brume.range_from_depth(marigold, kind="affine", far=40.0)
    assert "--" not in str(error.value)
    # The range fogs as any range in metres does.
    image = np.full((h, w, 3), 128, np.uint8)
    rng, _ = brume.range_from_depth(eye * 10, kind="depth", fov_y_deg=fov, scale=1.0)
    assert brume.fog(image, rng, beta=0.02, refine="none").shape == (h, w, 3)
    # float16, as a depth model run in half precision returns it: read exactly as the
    # float32 of the same values, here and as fog's range.
    half = (1.0 / eye).astype(np.float16)
    np.testing.assert_array_equal(
        brume.range_from_depth(half, kind="inverse", fov_y_deg=fov)[0],
        brume.range_from_depth(half.astype(np.float32), kind="inverse", fov_y_deg=fov)[0],
    )
    np.testing.assert_array_equal(
        brume.fog(image, rng.astype(np.float16), beta=0.02, refine="none"),
        brume.fog(image, rng.astype(np.float16).astype(np.float32), beta=0.02, refine="none"),
    )

    # The kind is required: an array does not say what it holds.
    with pytest.raises(TypeError, match="kind"):
        brume.range_from_depth(eye)
    with pytest.raises(ValueError, match="invalid kind = metres"):
        brume.range_from_depth(eye, kind="metres")
    with pytest.raises(ValueError, match="depth: expected shape HxW"):
        brume.range_from_depth(np.zeros((4, 4, 3)), kind="depth")
    with pytest.raises(ValueError, match="depth: expected dtype float32, float64 or float16"):
        brume.range_from_depth(np.zeros((4, 4), np.uint16), kind="depth")
    with pytest.raises(ValueError, match="depth: expected a numpy array"):
        brume.range_from_depth([[1.0]], kind="depth")
    with pytest.raises(ValueError, match="needs focal_px"):
        brume.range_from_depth(eye, kind="disparity")
    with pytest.raises(ValueError, match="no valid"):
        brume.range_from_depth(np.full((4, 4), np.nan), kind="range")

    # Depth without intrinsics is used as range, with a warning: in a 2:1 frame at a 45°
    # vertical field of view the corner's ray is sqrt(1 + 5 tan²(22.5°)) long.
    short = 100 * (1 - 1 / np.sqrt(1 + 5 * np.tan(np.radians(22.5)) ** 2))
    with pytest.warns(UserWarning, match=f"{short:.0f} % short in this 8x4 frame"):
        rng, info = brume.range_from_depth(np.full((4, 8), 5.0), kind="depth")
    np.testing.assert_array_equal(rng, 5.0)
    assert "no intrinsics: depth used as range" in info["notes"]
    # A monocular model's inverse depth is depth along the axis too.
    with pytest.warns(UserWarning, match="used as range for want of focal_px or fov_y_deg"):
        brume.range_from_depth(np.full((4, 8), 0.5), kind="inverse")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        brume.range_from_depth(np.full((4, 8), 5.0), kind="depth", fov_y_deg=45.0)
        brume.range_from_depth(np.full((4, 8), 5.0), kind="range")
    # A keyword given to no effect warns too: range needs no focal length.
    with pytest.warns(UserWarning, match="depth: focal_px ignored: the map already holds range"):
        brume.range_from_depth(np.full((4, 8), 5.0), kind="range", focal_px=500.0)
    # A street's inverse depth given as depth (larger toward the bottom, the road) is named,
    # with the keywords to give instead; its depth is not.
    rows = np.arange(60, dtype=np.float32)[:, None]
    street = np.broadcast_to(np.where(rows > 22, 75.0 / np.maximum(rows - 20, 1), 80.0),
                             (60, 40)).astype(np.float32)
    named = "grow toward the bottom.*focal_px and baseline_mm.*kind inverse"
    with pytest.warns(UserWarning, match=named):
        brume.range_from_depth(1.0 / street, kind="depth", fov_y_deg=45.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        brume.range_from_depth(street, kind="depth", fov_y_deg=45.0)


# --- equality with the `brume render` program ------------------------------------------




@pytest.mark.parametrize(
    "blur, refine, density",
    [
        (True, "none", dict(beta=0.02)),
        (False, "none", dict(beta=0.02)),
        (True, "repair", dict(beta=0.02)),
        (True, "guided", dict(beta=0.02)),
        # Paper 000's normalised haze, `brume render`'s default, with a blur strength.
        (True, "repair", dict(ka=0.3, ks=1.2, lambda_px=10.0)),
    ],
)
def test_equals_brume_render(tmp_path, image_u8, range_m, blur, refine, density):
    names = {"beta": "--beta", "ka": "--ka", "ks": "--ks", "lambda_px": "--lambda"}
    flags = ["--refine", refine]
    for key, value in density.items():
        flags += [names[key], str(value)]
    if not blur:
        flags += ["--lambda", "0"]
    cli = brume_render(tmp_path, image_u8, range_m, flags)
    ours = brume.fog(image_u8, range_m.astype(np.float32), blur=blur, refine=refine, **density)
    assert np.abs(ours.astype(np.int32) - cli.astype(np.int32)).max() <= 1


def render_cityscapes_frame(tmp_path, beta):
    """`brume render` of the Cityscapes frame f_leftImg8bit.png with f_disparity.png (and
    the camera file found beside it) in tmp_path, at extinction beta, unrefined, as
    uint8 sRGB."""
    Image = pytest.importorskip("PIL.Image")
    cmd = [
        str(brume_bin()), "render",
        "--image", str(tmp_path / "f_leftImg8bit.png"),
        "--depth", str(tmp_path / "f_disparity.png"),
        "--beta", str(beta), "--refine", "none",
        "--out", str(tmp_path / "cli.png"),
    ]  # fmt: skip
    subprocess.run(cmd, check=True, capture_output=True)
    return np.asarray(Image.open(tmp_path / "cli.png").convert("RGB"))


def test_a_cityscapes_disparitys_occlusions_as_brume_render_fills_them(tmp_path):
    """A pole (Z = 2 m, d = fx·B/Z = 25 px) before a wall (10 m, 5 px), the 20 px of wall
    left of it unknown as a matcher leaves what the right camera cannot see, the pole's
    disparity reaching 2 px over the wall on every other row: load_depth gives f·B, and
    fog with it fills the occlusion with the wall's range, as `brume render` fills the
    Cityscapes file; without it, the hole is a ramp to the pole."""
    Image = pytest.importorskip("PIL.Image")
    h, w, pole, band = 48, 96, (60, 66), (40, 60)
    x = np.arange(w)[None, :].repeat(h, 0)
    y = np.arange(h)[:, None].repeat(w, 1)
    in_pole = (x >= pole[0]) & (x < pole[1])
    fattened = (y % 2 == 1) & (x >= pole[0] - 2) & (x < pole[0])
    disparity = np.where(in_pole | fattened, 25.0, 5.0)
    disparity[(x >= band[0]) & (x < band[0] + 20) & ~fattened] = 0.0
    stored = np.where(disparity > 0, disparity * 256 + 1, 0).astype(np.uint16)
    Image.fromarray(stored).save(tmp_path / "f_disparity.png")
    camera = '{"extrinsic": {"baseline": 0.5}, "intrinsic": {"fx": 100.0, "fy": 100.0, "u0": 48.0, "v0": 24.0}}'
    (tmp_path / "f_camera.json").write_text(camera)
    brick = np.where(y % 4 == 0, 120, 130)[..., None] * np.array([1.0, 0.75, 0.5])
    image = np.where(in_pole[..., None], np.array([10, 10, 12]), brick).astype(np.uint8)
    Image.fromarray(image).save(tmp_path / "f_leftImg8bit.png")

    range_m, info = brume.load_depth(tmp_path / "f_disparity.png")
    assert info["format"] == "cityscapes" and info["stereo_focal_baseline"] == 50.0
    kw = dict(beta=0.05, refine="none", return_info=True)
    fb = info["stereo_focal_baseline"]
    ours, labels = brume.fog(image, range_m, stereo_focal_baseline=fb, **kw)
    _, as_hole = brume.fog(image, range_m, **kw)
    wall = range_m[:, band[0] - 1 : band[0]]
    fill = slice(band[0], pole[0] - 2)
    error = lambda got: np.abs(np.log(got[:, fill] / wall)).mean()  # noqa: E731
    assert error(labels["range_m"]) < 0.01
    assert error(as_hole["range_m"]) > 0.3
    cli = render_cityscapes_frame(tmp_path, 0.05)
    assert np.abs(ours.astype(np.int32) - cli.astype(np.int32)).max() <= 1
    with pytest.raises(ValueError, match="stereo_focal_baseline"):
        brume.fog(image, range_m, beta=0.05, stereo_focal_baseline=-1.0)

    # The right view's frame: the same mirrored, its occlusion right of the pole.
    Image.fromarray(stored[:, ::-1]).save(tmp_path / "r_disparity.png")
    (tmp_path / "r_camera.json").write_text(camera)
    right_m, right = brume.load_depth(tmp_path / "r_disparity.png", stereo_view="right")
    assert right["stereo_view"] == "right" and info["stereo_view"] == "left"
    image_r = np.ascontiguousarray(image[:, ::-1])
    origin = dict(stereo_focal_baseline=right["stereo_focal_baseline"])
    _, as_right = brume.fog(image_r, right_m, stereo_view=right["stereo_view"], **origin, **kw)
    _, as_left = brume.fog(image_r, right_m, **origin, **kw)
    # Row 0's run is no occlusion (the top band continues row 1's fattened edge beside the
    # pole), and a plane fitted to a hole whose other edges lie on one column fills it.
    mirrored = lambda got: got[1:, ::-1]  # noqa: E731
    wall_r = mirrored(right_m)[:, band[0] - 1 : band[0]]
    error_r = lambda got: np.abs(np.log(mirrored(got)[:, fill] / wall_r)).mean()  # noqa: E731
    assert error_r(as_right["range_m"]) < 0.01
    assert error_r(as_left["range_m"]) > 0.3
    with pytest.raises(ValueError, match="stereo_view"):
        brume.fog(image_r, right_m, stereo_view="centre", **origin, **kw)


def left_right_reference(image, other, disparity, sign, threshold=12 / 255):
    """Foggy Cityscapes' left-right check in numpy, on uint8 sRGB codes: image's pixel x
    against other's colour at x + sign·d (linear between its two nearest columns); unknown
    disparities and matches outside other pass. Also how far each pixel's largest
    difference lies from the threshold, to leave ties out of a comparison."""
    h, w = disparity.shape
    codes, other_codes = image / 255.0, other / 255.0
    x = np.arange(w)[None, :].repeat(h, 0)
    rows = np.arange(h)[:, None].repeat(w, 1)
    known = np.isfinite(disparity) & (disparity > 0)
    xr = x + sign * np.where(known, disparity, 0.0)
    seen = known & (xr >= 0) & (xr <= w - 1)
    x0 = np.clip(np.floor(xr), 0, w - 1).astype(int)
    x1 = np.minimum(x0 + 1, w - 1)
    t = (xr - x0)[..., None]
    match = other_codes[rows, x0] * (1 - t) + other_codes[rows, x1] * t
    diff = np.abs(codes - match).max(axis=2)
    return seen & (diff > threshold), np.abs(diff - threshold)


def test_left_right_mismatches_as_numpy_and_brume_render_find_them(tmp_path):
    """A textured pair 4 px apart: true disparities pass, wrong ones (9, 13.5 px, and
    random ones) fail where their match has another colour, as a numpy check finds them, for
    a left view and for the right view's disparity against the left image; and as many as
    `brume render --right` drops from the Cityscapes file."""
    Image = pytest.importorskip("PIL.Image")
    rng = np.random.default_rng(7)
    h, w = 12, 64
    u = np.arange(w + 4)[None, :] * 0.9 + np.arange(h)[:, None]
    scene = (127 + 100 * np.sin(u))[..., None] * np.array([1.0, 0.8, 0.5]) + 10
    left = np.ascontiguousarray(scene[:, :w]).astype(np.uint8)
    right = np.ascontiguousarray(scene[:, 4:]).astype(np.uint8)  # right(x) = left(x + 4)
    disparity = np.full((h, w), 4.0)
    wrong = rng.random((h, w)) < 0.2
    disparity[wrong] = rng.choice([9.0, 13.5, 2.25, 30.0], size=wrong.sum())
    disparity[3, 5], disparity[4, 6] = np.nan, 0.0
    for view, image, other, sign in [("left", left, right, -1), ("right", right, left, 1)]:
        got = brume.left_right_mismatches(image, other, disparity, stereo_view=view)
        assert got.dtype == np.bool_ and got.shape == (h, w)
        expected, margin = left_right_reference(image, other, disparity, sign)
        away = margin > 1e-3
        np.testing.assert_array_equal(got[away], expected[away], err_msg=view)
        assert not got[disparity == 4.0].any(), view
        assert 0.05 * wrong.sum() < got.sum() <= wrong.sum(), (view, got.sum())

    # brume render --right on the same frame as a Cityscapes file.
    stored = np.where(disparity > 0, disparity * 256 + 1, 0).astype(np.uint16)
    Image.fromarray(stored).save(tmp_path / "f_disparity.png")
    camera = '{"extrinsic": {"baseline": 0.2}, "intrinsic": {"fx": 100.0, "fy": 100.0, "u0": 32.0, "v0": 6.0}}'
    (tmp_path / "f_camera.json").write_text(camera)
    Image.fromarray(left).save(tmp_path / "f_leftImg8bit.png")
    Image.fromarray(right).save(tmp_path / "f_right.png")
    cmd = [
        str(brume_bin()), "render",
        "--image", str(tmp_path / "f_leftImg8bit.png"),
        "--depth", str(tmp_path / "f_disparity.png"),
        "--right", str(tmp_path / "f_right.png"),
        "--beta", "0.01", "--refine", "none", "--json",
        "--out", str(tmp_path / "cli.png"),
    ]  # fmt: skip
    report = json.loads(subprocess.run(cmd, check=True, capture_output=True).stdout)
    ours = brume.left_right_mismatches(left, right, disparity).sum()
    assert f"{ours} px failed the left-right check" in " ".join(report["depth_notes"])
    # load_depth's disparity_px: (p − 1)/256, NaN where p is 0 (and p = 1, d = 0).
    _, info = brume.load_depth(tmp_path / "f_disparity.png")
    want = np.where(disparity > 0, disparity, np.nan).astype(np.float32)
    np.testing.assert_array_equal(info["disparity_px"], want)
    _, info = brume.range_from_depth(disparity, kind="disparity", focal_px=100.0,
                                     baseline_mm=200.0)  # fmt: skip
    np.testing.assert_array_equal(info["disparity_px"], disparity.astype(np.float32))

    with pytest.raises(ValueError, match="stereo_view"):
        brume.left_right_mismatches(left, right, disparity, stereo_view="centre")
    with pytest.raises(ValueError, match="other"):
        brume.left_right_mismatches(left, right[:, 1:], disparity)
    with pytest.raises(ValueError, match="disparity_px"):
        brume.left_right_mismatches(left, right, disparity[1:])
    with pytest.raises(ValueError, match="threshold"):
        brume.left_right_mismatches(left, right, disparity, threshold=0.0)


def test_left_right_check_on_the_real_aloe_pair(tmp_path):
    """Middlebury's Aloe pair (tests/data/aloe: two JPEG views and the left view's ground
    truth, 0 unknown): load_depth gives the disparity as stored; the mask equals the numpy
    check away from ties; its ground truth
    fails at a minority of the pixels the check compares; and `brume render --right` reads
    the Middlebury 2006 PNG's disparity in pixels and drops as many."""
    Image = pytest.importorskip("PIL.Image")
    aloe = REPO / "tests/data/aloe"
    left = np.asarray(Image.open(aloe / "left.jpg").convert("RGB"))
    right = np.asarray(Image.open(aloe / "right.jpg").convert("RGB"))
    stored = np.asarray(Image.open(aloe / "disparity.png"))
    disparity = np.where(stored > 0, stored.astype(np.float64), np.nan)

    # load_depth gives the file's disparity in pixels beside the range.
    range_m, info = brume.load_depth(aloe / "disparity.png")
    np.testing.assert_array_equal(info["disparity_px"], disparity.astype(np.float32))
    got = brume.left_right_mismatches(left, right, info["disparity_px"])
    expected, margin = left_right_reference(left, right, disparity, -1)
    away = margin > 1e-3
    np.testing.assert_array_equal(got[away], expected[away])
    x = np.arange(disparity.shape[1])[None, :]
    checked = np.isfinite(disparity) & (x - np.nan_to_num(disparity) >= 0)
    assert 0.1 < got.sum() / checked.sum() < 0.3, got.sum() / checked.sum()

    # The views as PIL decoded them: JPEG decoders differ by a code here and there.
    Image.fromarray(left).save(tmp_path / "left.png")
    Image.fromarray(right).save(tmp_path / "right.png")
    cmd = [
        str(brume_bin()), "render",
        "--image", str(tmp_path / "left.png"), "--depth", str(aloe / "disparity.png"),
        "--right", str(tmp_path / "right.png"),
        "--ks", "0.5", "--refine", "none", "--json", "--out", str(tmp_path / "cli.png"),
    ]  # fmt: skip
    report = json.loads(subprocess.run(cmd, check=True, capture_output=True).stdout)
    notes = " ".join(report["depth_notes"])
    assert f"{got.sum()} px failed the left-right check" in notes
    assert f"of the {checked.sum()} px checked" in notes


def test_the_level_road_under_a_cityscapes_camera_as_brume_render_bounds_it(tmp_path):
    """A level road seen from 1.2 m up, pitched 0.04 rad down, the band along the left
    border unknown but for specks of 2 km touching the border on rows whose road is 4 to
    7 m off: load_depth gives the camera's mount, and fog with it fills the specks with the
    road, as `brume render` does with the camera file; without it they stay far."""
    Image = pytest.importorskip("PIL.Image")
    h, w, f, b, height, pitch = 96, 160, 200.0, 0.2, 1.2, 0.04
    x = np.arange(w)[None, :].repeat(h, 0)
    y = np.arange(h)[:, None].repeat(w, 1)
    v = (y - 48.0) / f
    drop = v * math.cos(pitch) + math.sin(pitch)
    road_z = np.where(drop > 0, height / np.maximum(drop, 1e-9), np.inf)
    disparity = f * b / np.minimum(road_z, 60.0)
    speck = (x < 5) & (y >= 70) & (y < 78)
    disparity[x < 24] = 0.0
    disparity[speck] = 0.02
    stored = np.where(disparity > 0, disparity * 256 + 1, 0).astype(np.uint16)
    Image.fromarray(stored).save(tmp_path / "f_disparity.png")
    camera = (
        f'{{"extrinsic": {{"baseline": {b}, "z": {height}, "pitch": {pitch}}}, '
        f'"intrinsic": {{"fx": {f}, "fy": {f}, "u0": 80.0, "v0": 48.0}}}}'
    )
    (tmp_path / "f_camera.json").write_text(camera)
    colour = np.where((road_z < 60.0)[..., None], [90, 90, 95], [150, 110, 80])
    image = colour.astype(np.uint8)
    Image.fromarray(image).save(tmp_path / "f_leftImg8bit.png")

    range_m, info = brume.load_depth(tmp_path / "f_disparity.png")
    want = dict(height_m=height, pitch=pitch, roll=0.0, fx=f, fy=f, cx=80.0, cy=48.0)
    assert info["ground"] == want
    kw = dict(beta=0.02, refine="none", return_info=True)
    ours, labels = brume.fog(image, range_m, ground=info["ground"], **kw)
    _, unbounded = brume.fog(image, range_m, **kw)
    road = road_z * np.sqrt(1.0 + ((x - 80.0) / f) ** 2 + v**2)
    error = lambda got: np.abs(np.log(got[speck] / road[speck])).mean()  # noqa: E731
    assert error(labels["range_m"]) < 0.05
    assert error(unbounded["range_m"]) > 1.0
    cli = render_cityscapes_frame(tmp_path, 0.02)
    assert np.abs(ours.astype(np.int32) - cli.astype(np.int32)).max() <= 1
    # RandomFog and albumentations' Fog pass it on to the fog.
    from brume.albumentations import Fog as AlbumentationsFog

    bounded = brume.fog(image, range_m, beta=0.02, refine="none", ground=info["ground"])
    random_fog = brume.augment.RandomFog(
        beta_dist="0.02", seed=0, refine="none", ground=info["ground"]
    )
    np.testing.assert_array_equal(random_fog(image=image, depth=range_m)["image"], bounded)
    assert "ground={" in repr(random_fog)
    fog = AlbumentationsFog(beta_dist="0.02", refine="none", ground=info["ground"])
    np.testing.assert_array_equal(fog.apply(image, beta=0.02, depth=range_m), bounded)
    assert "ground" in fog.get_transform_init_args_names()
    with pytest.raises(ValueError, match="ground: missing 'cy'"):
        brume.fog(image, range_m, beta=0.02, ground={k: want[k] for k in list(want)[:-1]})
    with pytest.raises(ValueError, match="height_m"):
        brume.fog(image, range_m, beta=0.02, ground=dict(want, height_m=-1.0))


def test_load_depth_camera_mount_gives_any_depth_map_the_level_road(tmp_path):
    """camera_mount=(height_m, pitch_deg[, roll_deg]) as `--camera-mount`: info's ground
    for a map with intrinsics (fov_y_deg) in metres; a map without intrinsics ignores it
    with a note; a bad value is a ValueError naming the keyword."""
    Image = pytest.importorskip("PIL.Image")
    depth_mm = np.full((48, 64), 5000, dtype=np.uint16)
    Image.fromarray(depth_mm).save(tmp_path / "d.png")
    kw = dict(format="png16", scale=0.001)
    _, info = brume.load_depth(tmp_path / "d.png", fov_y_deg=40.0, camera_mount=(1.2, 3.0), **kw)
    ground = info["ground"]
    assert (ground["height_m"], ground["roll"]) == (1.2, 0.0)
    assert math.isclose(ground["pitch"], math.radians(3.0))
    f = 24.0 / math.tan(math.radians(20.0))
    assert math.isclose(ground["fy"], f) and math.isclose(ground["cy"], 23.5)
    with pytest.warns(UserWarning) as caught:
        _, info = brume.load_depth(tmp_path / "d.png", camera_mount=(1.2, 3.0, 1.0), **kw)
    assert info["ground"] is None
    assert any("camera_mount ignored" in str(w.message) for w in caught), caught
    with pytest.raises(ValueError, match="camera_mount"):
        brume.load_depth(tmp_path / "d.png", fov_y_deg=40.0, camera_mount=(1.2, 95.0), **kw)


@pytest.mark.parametrize("airlight", [None, (0.6, 0.65, 0.7)])
def test_foggy_cityscapes_compat_equals_brume_render(tmp_path, image_u8, range_m, airlight):
    flags = ["--refine", "none", "--beta", "0.02", "--compat", "foggy-cityscapes"]
    if airlight is not None:
        flags += ["--airlight", ",".join(map(str, airlight))]
    cli = brume_render(tmp_path, image_u8, range_m, flags)
    kw = dict(beta=0.02, refine="none", compat="foggy-cityscapes", airlight=airlight)
    ours, info = brume.fog(image_u8, range_m, return_info=True, **kw)
    assert np.abs(ours.astype(np.int32) - cli.astype(np.int32)).max() <= 1
    # Its labels: t = exp(-beta R) and, in code values, I = R t + L (1 - t), L the
    # airlight reported, encoded.
    np.testing.assert_allclose(info["transmittance"], np.exp(-0.02 * info["range_m"]), rtol=1e-5)
    assert info["airlight_source"] == ("dark-channel" if airlight is None else "given")
    assert info["sigma_max_px"] == 0.0
    t = info["transmittance"][..., None].astype(np.float64)
    code = linear_to_srgb(np.array(info["airlight"]))
    expected = (image_u8 / 255.0) * t + code * (1.0 - t)
    assert np.abs(ours / 255.0 - expected).max() <= 1.0 / 255.0
    # Brume's own fog differs: linear light, and a blur.
    assert not np.array_equal(ours, brume.fog(image_u8, range_m, beta=0.02, refine="none"))


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(ks=0.75), "compat = 'foggy-cityscapes' and ka/ks: expected beta or visibility"),
        (dict(beta=0.02, lambda_px=4.0), "and lambda_px: expected no lambda_px"),
        (dict(beta=0.02, read_noise=0.01), "and the capture"),
        (dict(beta=0.02, compat="foggy"), "invalid compat = 'foggy'"),
    ],
)
def test_foggy_cityscapes_compat_refusals(image_u8, range_m, kwargs, message):
    kwargs.setdefault("compat", "foggy-cityscapes")
    with pytest.raises(ValueError, match=message):
        brume.fog(image_u8, range_m, **kwargs)


def test_capture_noise_has_the_model_variance(image_u8, range_m):
    # Linear float in and out, no blur: the noisy image minus the plain one has mean 0 and,
    # pixel by pixel, variance K·v + σ² (v the plain value), averaged here in numpy.
    linear = srgb_to_linear(image_u8 / 255.0).astype(np.float32) * 0.8
    opts = dict(beta=0.02, airlight=[0.7, 0.7, 0.7], blur=False, refine=False)
    plain = brume.fog(linear, range_m, **opts).astype(np.float64)
    k, sigma = 0.0005, 0.01
    noisy = brume.fog(linear, range_m, shot_noise_gain=k, read_noise=sigma, seed=5, **opts)
    d = noisy.astype(np.float64) - plain
    inside = (plain > 0.05) & (plain < 0.9)  # away from the clipping at 0 and 1
    d, v = d[inside], plain[inside]
    expected = float(np.mean(k * v + sigma**2))
    n = d.size
    assert abs(d.mean()) < 5 * math.sqrt(expected / n)
    # The variance's standard error for a near-normal difference: var·sqrt(2/n).
    assert abs(d.var() - expected) < 5 * expected * math.sqrt(2 / n), (d.var(), expected)
    again = brume.fog(linear, range_m, shot_noise_gain=k, read_noise=sigma, seed=5, **opts)
    np.testing.assert_array_equal(noisy, again)
    other = brume.fog(linear, range_m, shot_noise_gain=k, read_noise=sigma, seed=6, **opts)
    assert not np.array_equal(noisy, other)


def test_capture_exposure_and_jpeg(image_u8, range_m):
    opts = dict(beta=0.02, airlight=[0.7, 0.7, 0.7], blur=False, refine=False)
    linear = srgb_to_linear(image_u8 / 255.0).astype(np.float32)
    plain = brume.fog(linear, range_m, **opts)
    brighter = brume.fog(linear, range_m, exposure_stops=1.0, **opts)
    np.testing.assert_allclose(brighter, np.minimum(2.0 * plain, 1.0), atol=1e-6)
    jpeg = brume.fog(image_u8, range_m, jpeg_quality=30, **opts)
    assert jpeg.shape == image_u8.shape and jpeg.dtype == np.uint8
    clean = brume.fog(image_u8, range_m, **opts)
    diff = np.abs(jpeg.astype(int) - clean.astype(int))
    assert 0 < diff.mean() < 20
    for kwargs, message in [
        (dict(jpeg_quality=0), "jpeg_quality"),
        (dict(jpeg_quality=101), "jpeg_quality"),
        (dict(shot_noise_gain=-1.0), "shot_noise_gain"),
        (dict(read_noise=float("nan")), "read_noise"),
        (dict(exposure_stops=50.0), "exposure_stops"),
        (dict(seed=-1), "invalid seed = -1: expected a whole number"),
        (dict(seed=2**64), "invalid seed = 18446744073709551616"),
    ]:
        with pytest.raises(ValueError, match=message):
            brume.fog(image_u8, range_m, **opts, **kwargs)


def test_beta_dist_draws_follow_the_lognormal_quantiles(image_u8, range_m):
    from statistics import NormalDist

    mu, sigma = -4.6, 0.5
    dist = f"lognormal:{mu},{sigma}"
    # The quantile against Python's own normal distribution.
    for p in (0.01, 0.3, 0.5, 0.9, 0.999):
        expected = math.exp(mu + sigma * NormalDist().inv_cdf(p))
        assert abs(brume.beta_quantile(dist, p) - expected) < 1e-7 * expected
    assert brume.beta_quantile("uniform:0.005,0.03", 0.25) == pytest.approx(0.01125)
    # RandomFog: one draw for p, one for β's quantile, as numpy gives them.
    t = brume.augment.RandomFog(beta_dist=dist, seed=11, blur=False, refine=False)
    rng = np.random.default_rng(11)
    for _ in range(2):
        rng.random()
        expected = math.exp(mu + sigma * NormalDist().inv_cdf(rng.random()))
        out = t(image=image_u8, depth=range_m)
        assert out["beta"] == pytest.approx(expected, rel=1e-7)
    with pytest.raises(ValueError, match="beta_dist"):
        brume.augment.RandomFog(beta_dist="gamma:1,2")
    with pytest.raises(ValueError, match="beta_dist"):
        brume.beta_quantile("uniform:0.03,0.005", 0.5)


def test_random_fog_with_capture_is_seeded(image_u8, range_m):
    kw = dict(seed=2, blur=False, refine=False, read_noise=0.02, jpeg_quality=60)
    a = brume.augment.RandomFog(**kw)(image=image_u8, depth=range_m)
    b = brume.augment.RandomFog(**kw)(image=image_u8, depth=range_m)
    np.testing.assert_array_equal(a["image"], b["image"])
    plain = brume.augment.RandomFog(seed=2, blur=False, refine=False)(image=image_u8, depth=range_m)
    assert plain["beta"] == a["beta"]
    assert not np.array_equal(plain["image"], a["image"])


@pytest.mark.parametrize("name", ["fog", "distance_fog", "layered_fog", "aerial"])
def test_module_functions_have_their_methods_signatures(name):
    """brume.X calls Renderer.X on the default renderer: help() and IDEs must see the same
    keywords and defaults (not `*args, **kwargs`), and every default a value (not `...`,
    what PyO3 shows for a default that is not a literal)."""
    import inspect

    method = inspect.signature(getattr(brume.Renderer, name))
    params = list(method.parameters.values())
    assert params[0].name == "self"
    assert inspect.signature(getattr(brume, name)) == method.replace(parameters=params[1:])
    assert [p.name for p in params if p.default is Ellipsis] == []
    assert getattr(brume, name).__doc__.startswith(name + "(")


def test_type_stubs_match_the_module():
    """brume/_brume.pyi (what type checkers and IDEs read of the native module) names every
    public function, class, method and property of brume._brume, with the runtime's
    parameters, kinds and defaults."""
    import ast
    import inspect
    from pathlib import Path

    native = brume._brume
    stub = ast.parse((Path(brume.__file__).parent / "_brume.pyi").read_text())

    def stub_params(fn, drop_self):
        a = fn.args
        positional = a.posonlyargs + a.args
        defaults = [None] * (len(positional) - len(a.defaults)) + list(a.defaults)
        params = [(p.arg, "positional", d) for p, d in zip(positional, defaults)]
        params += [(p.arg, "keyword", d) for p, d in zip(a.kwonlyargs, a.kw_defaults)]
        params = params[1:] if drop_self else params
        return [(n, k, inspect.Parameter.empty if d is None else ast.literal_eval(d))
                for n, k, d in params]

    def runtime_params(obj):
        kinds = {inspect.Parameter.KEYWORD_ONLY: "keyword"}
        return [(p.name, kinds.get(p.kind, "positional"), p.default)
                for p in inspect.signature(obj).parameters.values() if p.name != "self"]

    def public(names):
        return {n for n in names if not n.startswith("_") or n in ("__version__", "__sources__")}

    stubbed = set()
    for node in stub.body:
        if isinstance(node, ast.FunctionDef):
            stubbed.add(node.name)
            assert stub_params(node, False) == runtime_params(getattr(native, node.name)), node.name
        elif isinstance(node, ast.ClassDef):
            stubbed.add(node.name)
            cls = getattr(native, node.name)
            members = set()
            for item in node.body:
                if not isinstance(item, ast.FunctionDef):
                    continue
                if item.name == "__init__":
                    assert stub_params(item, True) == runtime_params(cls), node.name
                    continue
                if item.name.startswith("__"):
                    assert hasattr(cls, item.name), f"{node.name}.{item.name}"
                    continue
                members.add(item.name)
                if not any(getattr(d, "id", None) == "property" for d in item.decorator_list):
                    assert stub_params(item, True) == runtime_params(getattr(cls, item.name)), (
                        f"{node.name}.{item.name}")
            assert members == public(dir(cls)), node.name
        elif isinstance(node, ast.AnnAssign) and node.target.id in ("__version__", "__sources__"):
            stubbed.add(node.target.id)
    assert stubbed == public(dir(native)) - {"Array", "PathArg"}


def test_renderer_closes(image_u8, range_m):
    """close() (and the end of a with block) ends the GL thread after what is queued and
    destroys the context; the renderer then refuses calls, and closing again is harmless."""
    with brume.Renderer() as renderer:
        expected = renderer.fog(image_u8, range_m, beta=0.01)
        assert not renderer.closed
    assert renderer.closed and "closed" in repr(renderer)
    with pytest.raises(RuntimeError, match="closed"):
        renderer.fog(image_u8, range_m, beta=0.01)
    renderer.close()
    np.testing.assert_array_equal(brume.Renderer().fog(image_u8, range_m, beta=0.01), expected)
    with pytest.raises(ValueError):  # an exception in the block goes on, the renderer closed
        with brume.Renderer() as renderer:
            renderer.fog(image_u8, range_m)
    assert renderer.closed


def ssim_reference(x, y):
    """Wang et al.'s SSIM of two grey float64 images in [0, 1], written with OpenCV's
    Gaussian filter: 11x11 window, sigma 1.5, K1 0.01, K2 0.03, L 1, the mean over the
    windows wholly inside the image."""
    cv2 = pytest.importorskip("cv2")
    blur = lambda im: cv2.GaussianBlur(im, (11, 11), 1.5)[5:-5, 5:-5]  # noqa: E731
    mx, my = blur(x), blur(y)
    vx, vy, cxy = blur(x * x) - mx**2, blur(y * y) - my**2, blur(x * y) - mx * my
    c1, c2 = 0.01**2, 0.03**2
    s = (2 * mx * my + c1) * (2 * cxy + c2) / ((mx**2 + my**2 + c1) * (vx + vy + c2))
    return s.mean()


def hsv_correlation_reference(a, b, bins=64):
    """The correlation of 64-bin hue, saturation and value histograms of two RGB images
    in [0, 1], HSV by OpenCV (hue in degrees)."""
    cv2 = pytest.importorskip("cv2")

    def histograms(im):
        hsv = cv2.cvtColor(im.astype(np.float32), cv2.COLOR_RGB2HSV).astype(np.float64)
        hsv[..., 0] /= 360
        index = np.minimum((hsv * bins).astype(int), bins - 1)
        return [np.bincount(index[..., c].ravel(), minlength=bins) for c in range(3)]

    return [np.corrcoef(p, q)[0, 1] for p, q in zip(histograms(a), histograms(b))]


def test_compare_is_ssim_and_hsv_correlation_as_numpy_and_brume_compare_say(tmp_path):
    """brume.compare of a linear photo with its fogged self and with a noisy copy: SSIM per
    channel of the sRGB values as written here with OpenCV's Gaussian (1e-6), the HSV
    histograms' correlation as numpy's (1e-9; float images, whose hues fall on no bin's
    edge, as 8-bit codes' often do exactly); of 8-bit PNGs, `brume compare`'s JSON number
    for number; sizes that differ or under 11 px raise."""
    Image = pytest.importorskip("PIL.Image")
    rng = np.random.default_rng(5)
    y, x = np.mgrid[0:H, 0:W]
    shown = np.stack([0.5 + 0.35 * np.sin(x / 5.0), 0.4 + 0.25 * np.cos(y / 3.0),
                      0.2 + (x + y) / 150.0], axis=2)  # fmt: skip
    a = srgb_to_linear(shown).astype(np.float32)
    noisy = np.clip(a + rng.normal(0, 0.03, a.shape), 0, 1).astype(np.float32)
    foggy = brume.fog(a, np.full((H, W), 5.0, np.float32) + x, beta=0.05, refine="none")
    for b in [noisy, foggy]:
        got = brume.compare(a, b)
        sa, sb = linear_to_srgb(a), linear_to_srgb(np.clip(b, 0, 1))
        want = [ssim_reference(sa[..., c], sb[..., c]) for c in range(3)]
        np.testing.assert_allclose(got["ssim_rgb"], want, atol=1e-6)
        assert got["ssim"] == pytest.approx(np.mean(want), abs=1e-6) and got["ssim"] < 0.99
        hsv = hsv_correlation_reference(sa, sb)
        np.testing.assert_allclose(got["hsv_correlation_hsv"], hsv, atol=1e-9)
    assert brume.compare(a, a)["ssim"] == pytest.approx(1.0, abs=1e-12)

    a8 = (linear_to_srgb(a) * 255 + 0.5).astype(np.uint8)
    foggy8 = brume.fog(a8, np.full((H, W), 5.0, np.float32) + x, beta=0.05, refine="none")
    Image.fromarray(a8).save(tmp_path / "a.png")
    Image.fromarray(foggy8).save(tmp_path / "b.png")
    cli = subprocess.run(
        [str(brume_bin()), "compare", str(tmp_path / "a.png"), str(tmp_path / "b.png"), "--json"],
        check=True, capture_output=True, text=True)  # fmt: skip
    report = json.loads(cli.stdout)
    got = brume.compare(a8, foggy8)
    for key in ["ssim", "ssim_rgb", "hsv_correlation", "hsv_correlation_hsv"]:
        assert got[key] == report[key], key

    with pytest.raises(ValueError, match="b"):
        brume.compare(a, a[:, 1:])
    with pytest.raises(ValueError, match="11x11"):
        brume.compare(a[:8, :8], a[:8, :8])


def test_prepare_is_brume_prep_and_the_range_fog_reads(tmp_path):
    """A monocular model's map of a sky over striped grass, metric, with a hole punched in
    the grass: prepare gives the range `brume prep --image` writes (equal), finite
    everywhere, and the ranges brume.fog's labels say it read with ks and with beta (its
    physical_range_m; unrefined: equal; repaired on the CPU against the GPU: 1e-4), also
    from a map half the image's size; its sky mask holds the sky rows, its filled mask the
    hole; bad keywords raise ValueError."""
    Image = pytest.importorskip("PIL.Image")
    h, w = 48, 64
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    eye = 2.0 + 0.3 * x + 0.2 * y
    image, disparity = sky_over_ground(eye, 0.002 + 0.00002 * np.arange(w))
    metric, _ = brume.range_from_depth(disparity, kind="inverse", fov_y_deg=60.0, scale=20.0)
    metric[30:36, 20:30] = np.nan
    for refine in ["none", "repair"]:
        got, info = brume.prepare(image, metric, refine=refine, monocular=True)
        assert got.dtype == np.float32 and got.shape == (h, w) and np.isfinite(got).all()
        assert info["refine"] == refine and not info["upsampled"]
        assert info["sky"][:12].all() and not info["sky"][14:].any(), refine
        assert info["filled"][30:36, 20:30].all() and info["holes"] >= 1
        assert info["filled"].sum() == info["hole_pixels"]
        kw = dict(refine=refine, monocular=True, return_info=True)
        _, physical = brume.fog(image, metric, beta=0.02, **kw)
        _, normalised = brume.fog(image, metric, ks=0.75, **kw)
        rtol = 1e-6 if refine == "none" else 1e-4
        np.testing.assert_allclose(info["physical_range_m"], physical["range_m"], rtol=rtol)
        np.testing.assert_allclose(got, normalised["range_m"], rtol=rtol)
        assert (info["physical_range_m"][0] == 1000.0).all() and got[0, 0] < 1000.0
        assert info["airlight"] == pytest.approx(physical["airlight"], abs=1e-7)

    # A map half the image's size is upsampled, guided by it, masks and all.
    big = np.repeat(np.repeat(image, 2, axis=0), 2, axis=1)
    got, info = brume.prepare(big, metric, monocular=True)
    assert got.shape == info["sky"].shape == info["filled"].shape == (2 * h, 2 * w)
    assert info["upsampled"] and np.isfinite(got).all()
    _, physical = brume.fog(big, metric, beta=0.02, monocular=True, return_info=True)
    np.testing.assert_allclose(info["physical_range_m"], physical["range_m"], rtol=1e-4)

    # brume prep --image of the same frame (its monocular map read as inverse depth).
    Image.fromarray(image).save(tmp_path / "image.png")
    np.save(tmp_path / "inverse.npy", disparity.astype(np.float32))
    cmd = [
        str(brume_bin()), "prep", "--image", str(tmp_path / "image.png"),
        "--depth", str(tmp_path / "inverse.npy"), "--depth-kind", "inverse",
        "--fov", "60", "--depth-scale", "20", "--out", str(tmp_path / "prep.pfm"),
    ]  # fmt: skip
    subprocess.run(cmd, check=True, capture_output=True)
    rng, _ = brume.range_from_depth(disparity, kind="inverse", fov_y_deg=60.0, scale=20.0)
    got, _ = brume.prepare(image, rng, monocular=True)
    written, _ = brume.load_depth(tmp_path / "prep.pfm", kind="range", scale=1.0,
                                  sky_beyond=float("inf"))  # fmt: skip
    np.testing.assert_array_equal(got, written)

    with pytest.raises(ValueError, match="refine"):
        brume.prepare(image, metric, refine="sharpen")
    with pytest.raises(ValueError, match="sky_mask"):
        brume.prepare(image, metric, sky_mask=np.ones((h, w), bool))
    with pytest.raises(ValueError, match="stereo_view"):
        brume.prepare(image, metric, stereo_focal_baseline=50.0, stereo_view="up")
