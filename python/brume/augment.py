"""Fog as a data augmentation, in the dict convention of albumentations and torchvision's
v2 transforms: ``t(image=..., depth=...)`` returns a dict with the fogged ``image``, the
``depth`` unchanged and the ``beta`` drawn.

    >>> t = RandomFog(beta_range=(0.005, 0.03), seed=0)
    >>> out = t(image=rgb_uint8, depth=range_m)
    >>> out["image"].shape == rgb_uint8.shape, out["beta"]

Pure Python on top of :func:`brume.fog`.
"""

from __future__ import annotations

from typing import Any, Optional, Sequence, Tuple

import numpy as np

from ._brume import Renderer, fog as _fog


class RandomFog:
    """Fog of a random density: β uniform in ``beta_range`` (1/m), drawn from a seeded
    :class:`numpy.random.Generator`; applied with probability ``p`` (else the image is
    returned as given and ``beta`` is ``None``).

    The other keywords go to :func:`brume.fog` as they are: ``airlight`` (None: estimated
    from the sky), ``blur``, ``refine``. ``renderer`` (a :class:`brume.Renderer`) lets
    several transforms or workers share or own a context; by default the module's.

    ``depth`` is the range in metres (HxW, the image's size or smaller by one factor).
    Extra keyword targets (masks, boxes) pass through unchanged.
    """

    def __init__(
        self,
        beta_range: Tuple[float, float] = (0.005, 0.03),
        seed: Optional[int] = None,
        p: float = 1.0,
        *,
        airlight: Optional[Sequence[float]] = None,
        blur: bool = True,
        refine: Any = True,
        renderer: Optional[Renderer] = None,
    ) -> None:
        lo, hi = (float(b) for b in beta_range)
        if not (np.isfinite(lo) and np.isfinite(hi) and 0.0 < lo <= hi):
            raise ValueError(
                f"invalid beta_range = {beta_range!r}: expected (low, high) with 0 < low <= high, in 1/m"
            )
        if not 0.0 <= float(p) <= 1.0:
            raise ValueError(f"invalid p = {p!r}: expected a probability in [0, 1]")
        self.beta_range = (lo, hi)
        self.p = float(p)
        self.airlight = airlight
        self.blur = blur
        self.refine = refine
        self.renderer = renderer
        self.rng = np.random.default_rng(seed)

    def __call__(self, *, image: np.ndarray, depth: np.ndarray, **targets: Any) -> dict:
        out = dict(targets)
        out["depth"] = depth
        # One draw for p and one for beta on every call, so that a seed gives the same
        # sequence of betas whatever p lets through.
        apply = self.rng.random() < self.p
        beta = float(self.rng.uniform(*self.beta_range))
        if not apply:
            out.update(image=image, beta=None)
            return out
        render = self.renderer.fog if self.renderer is not None else _fog
        out["image"] = render(
            image,
            depth,
            beta=beta,
            airlight=self.airlight,
            blur=self.blur,
            refine=self.refine,
        )
        out["beta"] = beta
        return out

    def __repr__(self) -> str:
        return (
            f"RandomFog(beta_range={self.beta_range}, p={self.p}, airlight={self.airlight}, "
            f"blur={self.blur}, refine={self.refine!r})"
        )
