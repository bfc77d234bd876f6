"""Type stubs of brume's native module (Rust, PyO3): the signatures that help(), IDEs and
type checkers read. python/tests/test_brume.py checks them against the module itself."""

from os import PathLike
from typing import Any, Dict, Optional, Sequence, Tuple, Union

from numpy.typing import NDArray

Array = NDArray[Any]
PathArg = Union[str, bytes, "PathLike[str]", "PathLike[bytes]"]

__version__: str
# The fingerprint of the sources this build was compiled from (brume --version shows it).
__sources__: str

class Camera:
    """brume's perspective camera of a rendered frame (`brume scene`'s)."""

    def __init__(
        self,
        position: Sequence[float] = (0.0, 1.7, 0.0),
        yaw_deg: float = 0.0,
        pitch_deg: float = 0.0,
        fov_y_deg: float = 60.0,
        near: float = 0.1,
        far: float = 1000.0,
    ) -> None: ...
    @property
    def position(self) -> Tuple[float, float, float]: ...
    @property
    def yaw_deg(self) -> float: ...
    @property
    def pitch_deg(self) -> float: ...
    @property
    def fov_y_deg(self) -> float: ...
    @property
    def near(self) -> float: ...
    @property
    def far(self) -> float: ...

class MatrixCamera:
    """An engine's camera from its view and projection matrices (4x4, row-major)."""

    def __init__(
        self,
        view: Array,
        projection: Array,
        clip: str = "minus_one_to_one",
        sky_depth: Optional[float] = None,
    ) -> None: ...
    @property
    def near(self) -> float: ...
    @property
    def far(self) -> float: ...
    @property
    def reversed(self) -> bool: ...
    @property
    def sky_depth(self) -> float: ...

class Renderer:
    """One EGL context kept for many frames (on a GL thread of its own)."""

    def __init__(self) -> None: ...
    @property
    def gl_renderer(self) -> str: ...
    @property
    def closed(self) -> bool: ...
    def close(self) -> None: ...
    def __enter__(self) -> "Renderer": ...
    def __exit__(self, kind: Any, value: Any, traceback: Any) -> bool: ...
    def fog(
        self,
        image: Array,
        range_m: Array,
        *,
        beta: Optional[Union[float, Sequence[float]]] = None,
        visibility: Optional[Union[float, Sequence[float]]] = None,
        ka: Optional[float] = None,
        ks: Optional[float] = None,
        airlight: Optional[Union[float, Sequence[float]]] = None,
        blur: bool = True,
        lambda_px: Optional[float] = None,
        refine: Union[bool, str, None] = None,
        sky_mask: Optional[Array] = None,
        ego_mask: Optional[Array] = None,
        exposure_stops: float = 0.0,
        shot_noise_gain: Optional[float] = None,
        read_noise: Optional[float] = None,
        jpeg_quality: Optional[int] = None,
        seed: int = 0,
        compat: Optional[str] = None,
        return_info: bool = False,
        monocular: bool = False,
        stereo_focal_baseline: Optional[float] = None,
        stereo_view: Optional[str] = None,
        ground: Optional[Dict[str, float]] = None,
    ) -> Any: ...
    def distance_fog(
        self,
        image: Array,
        depth: Array,
        *,
        camera: Union[Camera, MatrixCamera],
        time: float = 0.0,
        start_distance: Optional[float] = None,
        distance: Optional[float] = None,
        exponent: Optional[float] = None,
        max_density: Optional[float] = None,
        colour: Optional[Union[float, Sequence[float]]] = None,
        light_direction: Optional[Sequence[float]] = None,
        scatter_start: Optional[float] = None,
        scatter_exponent: Optional[float] = None,
        scatter_colour: Optional[Union[float, Sequence[float]]] = None,
        noise: Union[str, bool, PathArg, None] = None,
        noise_seed: int = 0,
        noise_size: Optional[float] = None,
        noise_speed: Optional[Sequence[float]] = None,
        noise_low: Optional[float] = None,
        noise_high: Optional[float] = None,
        noise_colour_strength: Optional[float] = None,
        blur: str = "diffusion",
        lambda_px: Optional[float] = None,
        range_unit: Optional[float] = None,
        sigma0: float = 1.0,
        scheme: str = "matched",
        precision: str = "f32",
        rho_max: float = 0.25,
        blur_distance: float = 100.0,
        blur_falloff: float = 1.0,
        blur_max: float = 1.0
    ) -> Array: ...
    def layered_fog(
        self,
        image: Array,
        depth: Array,
        *,
        camera: Union[Camera, MatrixCamera],
        time: float = 0.0,
        profile: str = "exponential",
        density: Optional[float] = None,
        base: Optional[float] = None,
        scale_height: Optional[float] = None,
        thickness: Optional[float] = None,
        top: Optional[float] = None,
        table: Union[PathArg, Array, None] = None,
        colour: Optional[Union[float, Sequence[float]]] = None,
        albedo: Optional[float] = None,
        blur: str = "diffusion",
        lambda_px: Optional[float] = None,
        range_unit: Optional[float] = None,
        sigma0: float = 1.0,
        scheme: str = "matched",
        precision: str = "f32",
        rho_max: float = 0.25,
        blur_distance: float = 100.0,
        blur_falloff: float = 1.0,
        blur_max: float = 1.0
    ) -> Array: ...
    def aerial(
        self,
        image: Array,
        range_m: Array,
        *,
        turbidity: Union[float, Sequence[float]],
        fov_y_deg: Optional[float] = None,
        focal_px: Optional[float] = None,
        pitch_deg: Optional[float] = None,
        horizon_row: Optional[float] = None,
        altitude_m: float = 0.0,
        metres_per_unit: float = 1.0,
        from_turbidity: Optional[float] = None,
        retarget: Optional[str] = None,
        airlight: Optional[Union[float, Sequence[float]]] = None,
        horizon_zenith_deg: float = 85.0,
        horizon_sectors: int = 8,
        sun: Optional[Tuple[float, float]] = None,
        sensitivity: Optional[PathArg] = None,
        icc_profile: Optional[bytes] = None,
        blur: bool = True,
        lambda_px: Optional[float] = 8.0,
        sigma0: float = 1.0,
        refine: Union[bool, str, None] = None,
        sky_mask: Optional[Array] = None,
        ego_mask: Optional[Array] = None,
        exposure_stops: float = 0.0,
        shot_noise_gain: Optional[float] = None,
        read_noise: Optional[float] = None,
        jpeg_quality: Optional[int] = None,
        seed: int = 0,
        return_info: bool = False,
        monocular: bool = False,
        stereo_focal_baseline: Optional[float] = None,
        stereo_view: Optional[str] = None,
        ground: Optional[Dict[str, float]] = None,
    ) -> Any: ...

def fog(
    image: Array,
    range_m: Array,
    *,
    beta: Optional[Union[float, Sequence[float]]] = None,
    visibility: Optional[Union[float, Sequence[float]]] = None,
    ka: Optional[float] = None,
    ks: Optional[float] = None,
    airlight: Optional[Union[float, Sequence[float]]] = None,
    blur: bool = True,
    lambda_px: Optional[float] = None,
    refine: Union[bool, str, None] = None,
    sky_mask: Optional[Array] = None,
    ego_mask: Optional[Array] = None,
    exposure_stops: float = 0.0,
    shot_noise_gain: Optional[float] = None,
    read_noise: Optional[float] = None,
    jpeg_quality: Optional[int] = None,
    seed: int = 0,
    compat: Optional[str] = None,
    return_info: bool = False,
    monocular: bool = False,
    stereo_focal_baseline: Optional[float] = None,
    stereo_view: Optional[str] = None,
    ground: Optional[Dict[str, float]] = None,
) -> Any: ...
def distance_fog(
    image: Array,
    depth: Array,
    *,
    camera: Union[Camera, MatrixCamera],
    time: float = 0.0,
    start_distance: Optional[float] = None,
    distance: Optional[float] = None,
    exponent: Optional[float] = None,
    max_density: Optional[float] = None,
    colour: Optional[Union[float, Sequence[float]]] = None,
    light_direction: Optional[Sequence[float]] = None,
    scatter_start: Optional[float] = None,
    scatter_exponent: Optional[float] = None,
    scatter_colour: Optional[Union[float, Sequence[float]]] = None,
    noise: Union[str, bool, PathArg, None] = None,
    noise_seed: int = 0,
    noise_size: Optional[float] = None,
    noise_speed: Optional[Sequence[float]] = None,
    noise_low: Optional[float] = None,
    noise_high: Optional[float] = None,
    noise_colour_strength: Optional[float] = None,
    blur: str = "diffusion",
    lambda_px: Optional[float] = None,
    range_unit: Optional[float] = None,
    sigma0: float = 1.0,
    scheme: str = "matched",
    precision: str = "f32",
    rho_max: float = 0.25,
    blur_distance: float = 100.0,
    blur_falloff: float = 1.0,
    blur_max: float = 1.0
) -> Array: ...
def layered_fog(
    image: Array,
    depth: Array,
    *,
    camera: Union[Camera, MatrixCamera],
    time: float = 0.0,
    profile: str = "exponential",
    density: Optional[float] = None,
    base: Optional[float] = None,
    scale_height: Optional[float] = None,
    thickness: Optional[float] = None,
    top: Optional[float] = None,
    table: Union[PathArg, Array, None] = None,
    colour: Optional[Union[float, Sequence[float]]] = None,
    albedo: Optional[float] = None,
    blur: str = "diffusion",
    lambda_px: Optional[float] = None,
    range_unit: Optional[float] = None,
    sigma0: float = 1.0,
    scheme: str = "matched",
    precision: str = "f32",
    rho_max: float = 0.25,
    blur_distance: float = 100.0,
    blur_falloff: float = 1.0,
    blur_max: float = 1.0
) -> Array: ...
def aerial(
    image: Array,
    range_m: Array,
    *,
    turbidity: Union[float, Sequence[float]],
    fov_y_deg: Optional[float] = None,
    focal_px: Optional[float] = None,
    pitch_deg: Optional[float] = None,
    horizon_row: Optional[float] = None,
    altitude_m: float = 0.0,
    metres_per_unit: float = 1.0,
    from_turbidity: Optional[float] = None,
    retarget: Optional[str] = None,
    airlight: Optional[Union[float, Sequence[float]]] = None,
    horizon_zenith_deg: float = 85.0,
    horizon_sectors: int = 8,
    sun: Optional[Tuple[float, float]] = None,
    sensitivity: Optional[PathArg] = None,
    icc_profile: Optional[bytes] = None,
    blur: bool = True,
    lambda_px: Optional[float] = 8.0,
    sigma0: float = 1.0,
    refine: Union[bool, str, None] = None,
    sky_mask: Optional[Array] = None,
    ego_mask: Optional[Array] = None,
    exposure_stops: float = 0.0,
    shot_noise_gain: Optional[float] = None,
    read_noise: Optional[float] = None,
    jpeg_quality: Optional[int] = None,
    seed: int = 0,
    return_info: bool = False,
    monocular: bool = False,
    stereo_focal_baseline: Optional[float] = None,
    stereo_view: Optional[str] = None,
    ground: Optional[Dict[str, float]] = None,
) -> Any: ...
def prepare(
    image: Array,
    range_m: Array,
    *,
    refine: Union[bool, str, None] = None,
    sky_mask: Optional[Array] = None,
    ego_mask: Optional[Array] = None,
    airlight: Optional[Union[float, Sequence[float]]] = None,
    monocular: bool = False,
    stereo_focal_baseline: Optional[float] = None,
    stereo_view: Optional[str] = None,
    ground: Optional[Dict[str, float]] = None,
) -> Tuple[Array, Dict[str, Any]]: ...
def load_photo(path: PathArg, *, dtype: str = "uint8") -> Tuple[Array, Dict[str, Any]]: ...
def save_photo(path: PathArg, image: Array, info: Optional[Dict[str, Any]] = None) -> None: ...
def turbidity_from_sky(
    path: PathArg,
    *,
    sun: Optional[Tuple[float, float]] = None,
    seed: int = 0,
    repeats: int = 10,
) -> Dict[str, Any]: ...
def render_sky(
    turbidity: float,
    *,
    sun: Tuple[float, float],
    size: int = 500,
    lens: str = "equidistant",
    counter_clockwise: bool = False,
    azimuth_offset_deg: float = 0.0,
    sun_disc_deg: Optional[float] = None,
    clouds: Optional[float] = None,
    cloud_seed: int = 0,
    dtype: str = "float32",
) -> Tuple[Array, Dict[str, Any]]: ...
def sun_position(
    latitude_deg: float,
    longitude_deg: float,
    time: Any,
    *,
    altitude_m: float = 0.0,
    pressure_hpa: float = 1013.25,
    temperature_c: float = 12.0,
    delta_t_s: Optional[float] = None,
) -> Dict[str, Any]: ...
def load_depth(
    path: PathArg,
    camera: Optional[PathArg] = None,
    format: Optional[str] = None,
    *,
    kind: Optional[str] = None,
    scale: Optional[float] = None,
    calib: Optional[PathArg] = None,
    focal_px: Optional[float] = None,
    baseline_mm: Optional[float] = None,
    disparity_offset_px: Optional[float] = None,
    near: Optional[float] = None,
    far: Optional[float] = None,
    fov_y_deg: Optional[float] = None,
    min_confidence: Optional[float] = None,
    reversed_z: bool = False,
    image: Optional[PathArg] = None,
    layout: Optional[str] = None,
    sky_beyond: Optional[float] = None,
    camera_mount: Optional[Tuple[float, ...]] = None,
    stereo_view: Optional[str] = None,
) -> Tuple[Array, Dict[str, Any]]: ...
def range_from_depth(
    depth: Array,
    *,
    kind: str,
    scale: Optional[float] = None,
    focal_px: Optional[float] = None,
    baseline_mm: Optional[float] = None,
    disparity_offset_px: Optional[float] = None,
    near: Optional[float] = None,
    far: Optional[float] = None,
    fov_y_deg: Optional[float] = None,
    reversed_z: bool = False,
    sky_beyond: Optional[float] = None,
) -> Tuple[Array, Dict[str, Any]]: ...
def left_right_mismatches(
    image: Array,
    other: Array,
    disparity_px: Array,
    *,
    stereo_view: str = "left",
    threshold: Optional[float] = None,
) -> Array: ...
def beta_quantile(dist: str, p: float) -> float: ...
def compare(a: Array, b: Array) -> Dict[str, Any]: ...
