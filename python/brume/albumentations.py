"""brume's fog as an albumentations transform (albumentations 2), for pipelines built with
``albumentations.Compose``, which takes only its own transforms:

    >>> import albumentations as A
    >>> from brume.albumentations import Fog
    >>> pipeline = A.Compose(
    ...     [Fog(beta_range=(0.005, 0.03)), A.HorizontalFlip(), A.RandomCrop(256, 256)],
    ...     additional_targets={"depth": "mask"},   # the range flipped and cropped too
    ...     seed=0,
    ... )
    >>> out = pipeline(image=rgb_uint8, depth=range_m)

The range in metres comes from the sample's ``depth`` as the transforms before ``Fog``
left it (declared as a mask target, geometric transforms resample it by nearest
neighbour, as a range must be); ``sky_mask`` and ``ego_mask``, when the sample has them,
go to the fog too. Put ``Fog`` before crops and resizes: the airlight is the sky's colour
in the image it gets, and the sky and holes take its largest range, so a crop changes
the fog of what it keeps (and a crop of sky alone has no range at all). β is drawn from
the pipeline's random generator, so ``Compose(seed=…)`` repeats it.
"""

from __future__ import annotations

from typing import Any, Optional, Sequence, Tuple, Union

import albumentations as A
import numpy as np

from ._brume import fog as _fog
from .augment import _checked_airlights, _checked_betas, _draw_airlight, _draw_beta

__all__ = ["Fog"]


class Fog(A.ImageOnlyTransform):
    """Fog of a random density on the image, from the sample's ``depth`` (HxW metres, the
    image's size or smaller by one factor): β uniform in ``beta_range`` (1/m), or drawn
    from ``beta_dist`` (``brume batch --beta-dist``'s ``"uniform:LOW,HIGH"``,
    ``"lognormal:MU,SIGMA"``), with probability ``p``. ``airlight``, ``blur``,
    ``refine``, ``compat``, ``monocular``, ``stereo_focal_baseline``, ``stereo_view`` and
    ``ground`` are :func:`brume.fog`'s; ``airlight_range`` draws a grey airlight in it
    instead, as :class:`brume.augment.RandomFog`'s. The image
    is uint8 sRGB or float32 linear RGB, as :func:`brume.fog` takes it: albumentations'
    ``ToFloat`` gives sRGB-encoded floats, which the fog would take for linear light, so
    put ``Fog`` before it.
    """

    def __init__(
        self,
        beta_range: Tuple[float, float] = (0.005, 0.03),
        *,
        beta_dist: Optional[str] = None,
        airlight: Optional[Union[float, Sequence[float]]] = None,
        airlight_range: Optional[Tuple[float, float]] = None,
        blur: bool = True,
        refine: Any = True,
        compat: Optional[str] = None,
        monocular: bool = False,
        stereo_focal_baseline: Optional[float] = None,
        stereo_view: Optional[str] = None,
        ground: Optional[dict] = None,
        p: float = 1.0,
    ) -> None:
        super().__init__(p=p)
        self.beta_range = _checked_betas(beta_range, beta_dist)
        self.beta_dist = beta_dist
        self.airlight = airlight
        self.airlight_range = _checked_airlights(airlight_range, airlight)
        self.blur = blur
        self.refine = refine
        self.compat = compat
        self.monocular = bool(monocular)
        self.stereo_focal_baseline = stereo_focal_baseline
        self.stereo_view = stereo_view
        self.ground = ground

    @property
    def targets_as_params(self) -> list:
        return ["depth"]

    def get_params_dependent_on_data(self, params: dict, data: dict) -> dict:
        return {
            "beta": _draw_beta(self.random_generator, self.beta_range, self.beta_dist),
            "airlight": _draw_airlight(self.random_generator, self.airlight_range, self.airlight),
            "depth": data["depth"],
            "sky_mask": data.get("sky_mask"),
            "ego_mask": data.get("ego_mask"),
        }

    def apply(
        self,
        img: np.ndarray,
        beta: float,
        depth: np.ndarray,
        airlight: Any = None,
        sky_mask: Optional[np.ndarray] = None,
        ego_mask: Optional[np.ndarray] = None,
        **params: Any,
    ) -> np.ndarray:
        return _fog(
            img,
            depth,
            beta=beta,
            airlight=airlight,
            blur=self.blur,
            refine=self.refine,
            compat=self.compat,
            monocular=self.monocular,
            stereo_focal_baseline=self.stereo_focal_baseline,
            stereo_view=self.stereo_view,
            ground=self.ground,
            sky_mask=sky_mask,
            ego_mask=ego_mask,
        )

    def get_transform_init_args_names(self) -> Tuple[str, ...]:
        return (
            "beta_range",
            "beta_dist",
            "airlight",
            "airlight_range",
            "blur",
            "refine",
            "compat",
            "monocular",
            "stereo_focal_baseline",
            "stereo_view",
            "ground",
        )
