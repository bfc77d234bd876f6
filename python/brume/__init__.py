"""brume: physically based haze and fog for photos with depth, on OpenGL ES through EGL.

    >>> import brume
    >>> foggy = brume.fog(image, range_m, beta=0.02)          # uint8 sRGB in, uint8 sRGB out
    >>> foggy = brume.fog(linear, range_m, visibility=150.0)  # float32 linear in, float32 out
    >>> foggy = brume.fog(image, relative_depth, ks=0.75)       # paper 000's normalised haze
    >>> foggy, info = brume.fog(image, range_m, beta=0.02, return_info=True)
    >>> info["transmittance"], info["airlight"]               # the labels: I = J t + A (1 - t)
    >>> filled, info = brume.prepare(image, range_m)  # the range fog reads, without the fog
    >>> range_m, info = brume.load_depth("frankfurt_000000_000294_disparity.png")
    >>> image, photo = brume.load_photo("IMG_0042.jpg")         # upright, by its profile
    >>> brume.save_photo("foggy.jpg", brume.fog(image, range_m, beta=0.02), photo)
    >>> range_m, info = brume.range_from_depth(z_m, kind="depth", fov_y_deg=60.0)  # an array
    >>> range_m[brume.left_right_mismatches(left, right, disparity_px)] = np.nan  # filled
    >>> r = brume.Renderer()                                  # one EGL context, many frames
    >>> t = brume.augment.RandomFog(beta_range=(0.005, 0.03), seed=0)
    >>> out = t(image=image, depth=range_m)                   # {"image", "depth", "beta"}
    >>> noisy = brume.fog(image, range_m, beta=0.02, read_noise=0.01, jpeg_quality=80, seed=1)

The engine fogs on a rendered frame and its depth buffer (window depth in [0, 1]):

    >>> cam = brume.Camera(position=(0, 1.7, 0), yaw_deg=30, pitch_deg=-5, fov_y_deg=60)
    >>> out = brume.distance_fog(frame, depth, camera=cam, time=2.5)          # paper 001
    >>> out = brume.layered_fog(frame, depth, camera=cam, profile="band")     # paper 003
    >>> cam = brume.MatrixCamera(view, projection, clip="zero_to_one")        # an engine's

Aerial perspective from turbidity on a photo with range in metres (paper 002):

    >>> hazy = brume.aerial(image, range_m, turbidity=4.0, fov_y_deg=50.0, pitch_deg=2.0)
    >>> t = brume.turbidity_from_sky("fisheye.exr", sun=(40.0, 120.0))["turbidity"]
    >>> sky, info = brume.render_sky(4.0, sun=(40.0, 120.0), clouds=0.2)  # kcd/m², float32
    >>> s = brume.sun_position(48.85, 2.35, "2024-06-21T10:00:00+02:00")  # NREL's SPA

The native part is ``brume._brume`` (Rust, PyO3); see the repository's README, "Python".
"""

from ._brume import (
    Camera,
    MatrixCamera,
    Renderer,
    __sources__,
    __version__,
    aerial,
    beta_quantile,
    compare,
    distance_fog,
    fog,
    layered_fog,
    left_right_mismatches,
    load_depth,
    load_photo,
    prepare,
    range_from_depth,
    render_sky,
    save_photo,
    sun_position,
    turbidity_from_sky,
)
from . import augment

__all__ = [
    "Renderer",
    "fog",
    "prepare",
    "load_depth",
    "load_photo",
    "save_photo",
    "range_from_depth",
    "left_right_mismatches",
    "beta_quantile",
    "compare",
    "distance_fog",
    "layered_fog",
    "aerial",
    "turbidity_from_sky",
    "render_sky",
    "sun_position",
    "Camera",
    "MatrixCamera",
    "augment",
    "__version__",
    "__sources__",
]
