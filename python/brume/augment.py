"""Fog as a data augmentation, in the dict convention of albumentations and torchvision's
v2 transforms: ``t(image=..., depth=...)``, or ``t(sample)`` with a dict of the same keys
(as torchvision v2's ``Compose`` calls its transforms), returns a dict with the fogged
``image``, the ``depth`` unchanged and the ``beta`` drawn (with ``return_info=True`` also
the ``transmittance`` and ``airlight`` labels of a dehazing dataset).

    >>> t = RandomFog(beta_range=(0.005, 0.03), seed=0)
    >>> out = t(image=rgb_uint8, depth=range_m)
    >>> out["image"].shape == rgb_uint8.shape, out["beta"]
    >>> out = t({"image": rgb_uint8, "depth": range_m})   # as torchvision v2's Compose calls it

Inside ``albumentations.Compose``, which takes only its own transforms, use
:class:`brume.albumentations.Fog`. Pure Python on top of :func:`brume.fog`.
"""

from __future__ import annotations

import os
import sys
from typing import Any, Dict, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from ._brume import Renderer, beta_quantile, fog as _fog


class RandomFog:
    """Fog of a random density: β uniform in ``beta_range`` (1/m), or drawn from
    ``beta_dist`` (``"uniform:LOW,HIGH"``, ``"lognormal:MU,SIGMA"`` with ln β normal, or
    ``"0.02"``, as ``brume batch --beta-dist``), from a seeded
    :class:`numpy.random.Generator`; applied with probability ``p`` (else the image is
    returned as given and ``beta`` is ``None``).

    The camera after the fog, as :func:`brume.fog`'s keywords of the same names (all off
    by default): ``exposure_stops``, ``shot_noise_gain``, ``read_noise`` (the noise's seed
    drawn from the generator on each call) and ``jpeg_quality``.

    The other keywords go to :func:`brume.fog` as they are: ``airlight`` (None: estimated
    from the sky; a grey or linear RGB), ``blur``, ``refine``, ``compat``
    (``'foggy-cityscapes'``: Foggy Cityscapes' blend). ``airlight_range=(low, high)``
    draws a grey airlight uniformly in it on each call instead (linear light, as every
    brume airlight: RESIDE's A in [0.7, 1] of code values is about (0.45, 1.0)).
    ``renderer`` (a :class:`brume.Renderer`) lets several transforms or workers share or
    own a context; by default the module's.

    ``depth`` is the range in metres (HxW, HxWx1 or 1xHxW, the image's size or smaller by
    one factor); ``monocular=True`` when it comes from a monocular model's relative depth
    (:func:`brume.range_from_depth` with ``kind='inverse'`` or ``'affine'``), whose sky has
    a depth: :func:`brume.fog`'s ``monocular``; ``stereo_focal_baseline`` (f·B, px·m) when
    it comes from a stereo-matched disparity (a Cityscapes disparity:
    :func:`brume.load_depth`'s info gives it), whose occlusions are then filled from their
    background on the side ``stereo_view`` says (``'left'``, the default, or ``'right'``;
    that info gives it too), and ``ground`` (that info's ``ground``: the level road under a
    Cityscapes camera), which bounds its range below the horizon: :func:`brume.fog`'s.
    Fog whole frames and crop after: the airlight and the range of the sky come from the
    image the fog gets.
    Extra keyword targets (masks, boxes) pass through unchanged; ``sky_mask`` and
    ``ego_mask`` targets (the depth's shape, non-zero = set) also go to
    :func:`brume.fog`: the sky instead of its detection, the car's hood never fogged.

    In a PyTorch ``DataLoader`` worker the generator is seeded again, from ``seed`` and
    the worker's seed (``torch.utils.data.get_worker_info().seed``, which differs between
    workers and follows ``torch.manual_seed``): each worker holds a copy of the transform,
    and the copies would otherwise draw the same betas. Without a seed, a copy in any
    other process (``multiprocessing``) draws from fresh entropy; with one, it repeats
    the seed's draws, as asked.

    ``return_info=True`` adds the labels of the scattering model I = J·t + A·(1 − t), as
    :func:`brume.fog` reports them: ``transmittance`` (float32 HxW at the image's size;
    all ones when the fog is not applied) and ``airlight`` (A, three linear RGB floats;
    ``None`` when not applied).
    """

    def __init__(
        self,
        beta_range: Tuple[float, float] = (0.005, 0.03),
        seed: Optional[int] = None,
        p: float = 1.0,
        *,
        airlight: Optional[Union[float, Sequence[float]]] = None,
        airlight_range: Optional[Tuple[float, float]] = None,
        blur: bool = True,
        refine: Any = True,
        compat: Optional[str] = None,
        renderer: Optional[Renderer] = None,
        beta_dist: Optional[str] = None,
        exposure_stops: float = 0.0,
        shot_noise_gain: Optional[float] = None,
        read_noise: Optional[float] = None,
        jpeg_quality: Optional[int] = None,
        return_info: bool = False,
        monocular: bool = False,
        stereo_focal_baseline: Optional[float] = None,
        stereo_view: Optional[str] = None,
        ground: Optional[dict] = None,
    ) -> None:
        self.beta_range = _checked_betas(beta_range, beta_dist)
        if not 0.0 <= float(p) <= 1.0:
            raise ValueError(f"invalid p = {p!r}: expected a probability in [0, 1]")
        self.p = float(p)
        self.airlight = airlight
        self.airlight_range = _checked_airlights(airlight_range, airlight)
        self.blur = blur
        self.refine = refine
        self.compat = compat
        self.renderer = renderer
        self.beta_dist = beta_dist
        self.capture: Dict[str, Any] = dict(
            exposure_stops=float(exposure_stops),
            shot_noise_gain=shot_noise_gain,
            read_noise=read_noise,
            jpeg_quality=jpeg_quality,
        )
        self.return_info = bool(return_info)
        self.monocular = bool(monocular)
        self.stereo_focal_baseline = stereo_focal_baseline
        self.stereo_view = stereo_view
        self.ground = ground
        self.seed = seed
        self.rng = np.random.default_rng(seed)
        self._worker: Optional[int] = None
        self._pid = os.getpid()

    def __call__(self, sample: Optional[Mapping[str, Any]] = None, /, **targets: Any) -> dict:
        """``t(image=…, depth=…, **targets)`` (albumentations' convention), or ``t(sample)``
        with the same keys in one dict (torchvision v2's ``Compose`` passes a dict sample
        this way). ``image`` is a numpy array or a PIL image (fogged in RGB, returned as a
        PIL image)."""
        if sample is not None:
            if targets or not isinstance(sample, Mapping):
                raise TypeError(
                    "RandomFog takes image=…, depth=… as keywords, or one dict of them, not both"
                )
            targets = dict(sample)
        missing = [k for k in ("image", "depth") if targets.get(k) is None]
        if missing:
            raise TypeError(f"RandomFog needs {' and '.join(missing)}: t(image=…, depth=range_m)")
        given, depth = targets.pop("image"), targets.pop("depth")
        pil = _pil_image_class(given)
        image = np.asarray(given.convert("RGB")) if pil is not None else given
        out = self._fog(image, depth, targets)
        if pil is not None:
            out["image"] = given if out["image"] is image else pil.fromarray(out["image"])
        return out

    def _fog(self, image: np.ndarray, depth: np.ndarray, targets: dict) -> dict:
        out = dict(targets)
        out["depth"] = depth
        self._reseed_in_worker()
        # One draw for p and one for beta on every call, so that a seed gives the same
        # sequence of betas whatever p lets through.
        apply = self.rng.random() < self.p
        beta = _draw_beta(self.rng, self.beta_range, self.beta_dist)
        noisy = self.capture["shot_noise_gain"] is not None or self.capture["read_noise"] is not None
        # Drawn only with noise, so that a seed without it gives the betas it always gave.
        noise_seed = int(self.rng.integers(0, 2**63)) if noisy else 0
        # Drawn only with a range, after the others, for the same reason.
        airlight = _draw_airlight(self.rng, self.airlight_range, self.airlight)
        if not apply:
            out.update(image=image, beta=None)
            if self.return_info:
                out.update(transmittance=np.ones(image.shape[:2], np.float32), airlight=None)
            return out
        render = self.renderer.fog if self.renderer is not None else _fog
        fogged = render(
            image,
            depth,
            beta=beta,
            airlight=airlight,
            blur=self.blur,
            refine=self.refine,
            compat=self.compat,
            seed=noise_seed,
            sky_mask=targets.get("sky_mask"),
            ego_mask=targets.get("ego_mask"),
            return_info=self.return_info,
            monocular=self.monocular,
            stereo_focal_baseline=self.stereo_focal_baseline,
            stereo_view=self.stereo_view,
            ground=self.ground,
            **self.capture,
        )
        if self.return_info:
            fogged, info = fogged
            out.update(transmittance=info["transmittance"], airlight=tuple(info["airlight"]))
        out["image"] = fogged
        out["beta"] = beta
        return out

    def __repr__(self) -> str:
        return (
            f"RandomFog(beta_range={self.beta_range}, beta_dist={self.beta_dist!r}, p={self.p}, "
            f"airlight={self.airlight}, airlight_range={self.airlight_range}, "
            f"blur={self.blur}, refine={self.refine!r}, compat={self.compat!r}, "
            f"capture={self.capture}, return_info={self.return_info}, "
            f"monocular={self.monocular}, "
            f"stereo_focal_baseline={self.stereo_focal_baseline}, "
            f"stereo_view={self.stereo_view!r}, "
            f"ground={self.ground})"
        )

    def _reseed_in_worker(self) -> None:
        torch = sys.modules.get("torch")  # imported by the DataLoader that runs a worker
        info = torch.utils.data.get_worker_info() if torch is not None else None
        if info is not None:
            if info.seed != self._worker:
                self._worker = info.seed
                entropy = [info.seed] if self.seed is None else [self.seed, info.seed]
                self.rng = np.random.default_rng(entropy)
        elif self.seed is None and os.getpid() != self._pid:
            # Another process's copy (multiprocessing): fresh entropy, as the unseeded
            # transform had when it was made, rather than the parent's stream again.
            self._pid = os.getpid()
            self.rng = np.random.default_rng()


def _checked_betas(
    beta_range: Tuple[float, float], beta_dist: Optional[str]
) -> Tuple[float, float]:
    """``beta_range`` as two floats, after checking it and ``beta_dist`` (a ValueError that
    says what is expected)."""
    if beta_dist is not None:
        beta_quantile(beta_dist, 0.5)
    lo, hi = (float(b) for b in beta_range)
    if not (np.isfinite(lo) and np.isfinite(hi) and 0.0 < lo <= hi):
        raise ValueError(
            f"invalid beta_range = {beta_range!r}: expected (low, high) with 0 < low <= high, in 1/m"
        )
    return lo, hi


def _checked_airlights(
    airlight_range: Optional[Tuple[float, float]], airlight: Any
) -> Optional[Tuple[float, float]]:
    """``airlight_range`` as two floats (or None), refused with an ``airlight`` given."""
    if airlight_range is None:
        return None
    if airlight is not None:
        raise ValueError(
            f"airlight = {airlight!r} and airlight_range = {airlight_range!r} both given: "
            "expected one (a fixed airlight, or a grey drawn on each call)"
        )
    lo, hi = (float(a) for a in airlight_range)
    if not (np.isfinite(lo) and np.isfinite(hi) and 0.0 <= lo <= hi):
        raise ValueError(
            f"invalid airlight_range = {airlight_range!r}: expected (low, high) with "
            "0 <= low <= high, linear light"
        )
    return lo, hi


def _draw_airlight(
    rng: np.random.Generator, airlight_range: Optional[Tuple[float, float]], airlight: Any
) -> Any:
    """A grey uniform in ``airlight_range``, or ``airlight`` as given without a range."""
    if airlight_range is None:
        return airlight
    return float(rng.uniform(*airlight_range))


def _draw_beta(
    rng: np.random.Generator, beta_range: Tuple[float, float], beta_dist: Optional[str]
) -> float:
    """β uniform in ``beta_range``, or from ``beta_dist`` (a uniform p in (0, 1) through
    the distribution's quantile, brume's own)."""
    if beta_dist is None:
        return float(rng.uniform(*beta_range))
    p = min(max(float(rng.random()), 1e-16), 1.0 - 1e-16)
    return float(beta_quantile(beta_dist, p))


def _pil_image_class(image: Any) -> Any:
    """PIL's ``Image`` module if ``image`` is a PIL image, else ``None`` (PIL is optional)."""
    module = type(image).__module__
    if not module.startswith("PIL."):
        return None
    from PIL import Image

    return Image if isinstance(image, Image.Image) else None
