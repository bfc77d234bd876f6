"""brume: physically based haze and fog for photos with depth, on OpenGL ES through EGL.

    >>> import brume
    >>> foggy = brume.fog(image, range_m, beta=0.02)          # uint8 sRGB in, uint8 sRGB out
    >>> foggy = brume.fog(linear, range_m, visibility=150.0)  # float32 linear in, float32 out
    >>> range_m, info = brume.load_depth("frankfurt_000000_000294_disparity.png")
    >>> r = brume.Renderer()                                  # one EGL context, many frames
    >>> t = brume.augment.RandomFog(beta_range=(0.005, 0.03), seed=0)
    >>> out = t(image=image, depth=range_m)                   # {"image", "depth", "beta"}
    >>> noisy = brume.fog(image, range_m, beta=0.02, read_noise=0.01, jpeg_quality=80, seed=1)

The native part is ``brume._brume`` (Rust, PyO3); see the repository's README, "Python".
"""

from ._brume import Renderer, __version__, beta_quantile, fog, load_depth
from . import augment

__all__ = ["Renderer", "fog", "load_depth", "beta_quantile", "augment", "__version__"]
