//! Virtual objects in foggy photos (`photo::insert`, `brume render --insert`): a square of
//! known range, partly covering, partly behind the photo's surface. Occlusion is checked
//! pixel by pixel against the rule computed here, and the fogged pixels against
//! τ(R)·J + (1 − τ)·A with τ = exp(−β·R), computed here from the inputs.

use crate::common;

use brume::io::camera::Intrinsics;
use brume::io::depth::DepthKind;
use brume::photo::{self, FogOptions, Photo, PrepareOptions, VirtualObject};
use brume::raster::{Grid, RgbImage, RgbaImage, ScalarMap};
use common::{exr_bytes, f32s};

const W: usize = 32;
const H: usize = 24;
/// The photo: a grey wall at 5 m on the left half, at 20 m on the right half.
const NEAR_M: f32 = 5.0;
const FAR_M: f32 = 20.0;
const WALL: [f32; 3] = [0.3, 0.35, 0.4];
/// The object: a square at 10 m, in front of the far half, behind the near half.
const OBJECT_M: f32 = 10.0;
const RED: [f32; 3] = [0.8, 0.1, 0.05];
const AIRLIGHT: [f32; 3] = [0.7, 0.75, 0.8];
const BETA: f64 = 0.08;

fn photo_image() -> RgbImage {
    Grid::filled(W, H, WALL)
}

fn photo_range() -> ScalarMap {
    Grid::from_fn(W, H, |x, _| if x < W / 2 { NEAR_M } else { FAR_M })
}

/// The object's coverage: the square x in 8..26, y in 6..18; its column 25 half covered,
/// column 24 a quarter, the rest full.
fn coverage(x: usize, y: usize) -> f32 {
    if !(8..26).contains(&x) || !(6..18).contains(&y) {
        return 0.0;
    }
    match x {
        25 => 0.5,
        24 => 0.25,
        _ => 1.0,
    }
}

/// Premultiplied RGBA of the object.
fn object_rgba() -> RgbaImage {
    Grid::from_fn(W, H, |x, y| {
        let a = coverage(x, y);
        [RED[0] * a, RED[1] * a, RED[2] * a, a]
    })
}

fn object_range() -> ScalarMap {
    Grid::from_fn(W, H, |x, y| {
        if coverage(x, y) > 0.0 {
            OBJECT_M
        } else {
            f32::INFINITY
        }
    })
}

/// What a pixel should be after compositing, by the rule itself: colour and range.
fn expected_composite(x: usize, y: usize) -> ([f32; 3], f32) {
    let a = coverage(x, y);
    let r_photo = *photo_range().get(x, y);
    if a == 0.0 || OBJECT_M >= r_photo {
        return (WALL, r_photo);
    }
    let colour = [0, 1, 2].map(|k| RED[k] * a + (1.0 - a) * WALL[k]);
    (colour, if a >= 0.5 { OBJECT_M } else { r_photo })
}

#[test]
fn the_object_shows_only_where_it_is_nearer() {
    let object = VirtualObject::from_range(object_rgba(), object_range(), "square").unwrap();
    let mut image = photo_image();
    let mut range = photo_range();
    let done = object.composite(&mut image, &mut range).unwrap();
    // Square 18 x 12: 8 columns (8..16) behind the 5 m wall, 10 in front (16..26) of
    // which 2 partly covered.
    assert_eq!(done.hidden, 8 * 12);
    assert_eq!(done.in_front, 8 * 12);
    assert_eq!(done.partial, 2 * 12);
    for y in 0..H {
        for x in 0..W {
            let (colour, r) = expected_composite(x, y);
            let got = image.get(x, y);
            for k in 0..3 {
                assert!(
                    (got[k] - colour[k]).abs() < 1e-6,
                    "({x}, {y}): {got:?} vs {colour:?}"
                );
            }
            assert_eq!(*range.get(x, y), r, "range at ({x}, {y})");
        }
    }
}

#[test]
fn the_object_is_fogged_by_the_photos_medium() {
    let (_gl, mut headless) = common::renderer();
    let mut photo = Photo::from_range(photo_image(), photo_range()).unwrap();
    let prepare = PrepareOptions {
        prep: None,
        airlight: Some(AIRLIGHT),
        ..PrepareOptions::default()
    };
    let mut prepared = photo::preprocess(&photo, &prepare).unwrap();
    let object = VirtualObject::from_range(object_rgba(), object_range(), "square").unwrap();
    photo::insert(&mut photo, &mut prepared, &object).unwrap();
    let opts = FogOptions {
        lambda: 0.0,
        ..FogOptions::beta(BETA).unwrap()
    };
    let fogged = photo::fog(headless.renderer().unwrap(), &photo, &prepared, &opts).unwrap();
    let out = &fogged.rendered.image;
    let mut checked_object = 0;
    for y in 0..H {
        for x in 0..W {
            let (j, r) = expected_composite(x, y);
            let tau = (-BETA * f64::from(r)).exp() as f32;
            let got = out.get(x, y);
            for k in 0..3 {
                let expected = tau * j[k] + (1.0 - tau) * AIRLIGHT[k];
                assert!(
                    (got[k] - expected).abs() < 2e-4,
                    "({x}, {y}) channel {k}: {} vs τ·J + (1 − τ)·A = {expected} (τ {tau})",
                    got[k]
                );
            }
            checked_object += usize::from(r == OBJECT_M && coverage(x, y) == 1.0);
        }
    }
    assert_eq!(checked_object, 8 * 12);
    // The object pixel and the wall beside it differ as the formula says, not by chance:
    // the object at 10 m is less veiled than the far wall at 20 m.
    let (obj, wall) = (out.get(20, 10)[0], out.get(28, 10)[0]);
    assert!(obj > wall + 0.05, "object {obj} vs far wall {wall}");
}

#[test]
fn depth_along_the_axis_becomes_range_along_the_ray() {
    let k = Intrinsics::centred(40.0, W, H);
    let depth = Grid::filled(W, H, 10.0f32);
    let object = VirtualObject::from_depth(object_rgba(), depth, &k, "square").unwrap();
    for (x, y) in [(0, 0), (W - 1, 3), (15, 11)] {
        let (u, v) = (
            (x as f64 - (W as f64 - 1.0) / 2.0) / 40.0,
            (y as f64 - (H as f64 - 1.0) / 2.0) / 40.0,
        );
        let expected = 10.0 * (1.0 + u * u + v * v).sqrt();
        let got = f64::from(*object.range.get(x, y));
        assert!(
            (got - expected).abs() < 1e-4,
            "({x}, {y}): {got} vs {expected}"
        );
    }
}

#[test]
fn an_object_of_another_size_is_refused() {
    let small = VirtualObject::from_range(
        Grid::filled(8, 8, [0.0; 4]),
        Grid::filled(8, 8, 1.0),
        "small.exr",
    )
    .unwrap();
    let e = small
        .composite(&mut photo_image(), &mut photo_range())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("small.exr") && e.contains("8x8") && e.contains("32x24"),
        "{e}"
    );
    let e = VirtualObject::from_range(Grid::filled(8, 8, [0.0; 4]), Grid::filled(8, 4, 1.0), "o")
        .unwrap_err()
        .to_string();
    assert!(e.contains("8x4") && e.contains("8x8"), "{e}");
}

/// The object as a flat R, G, B, A (+ Z) EXR, as a compositor writes it.
fn object_exr(with_z: bool) -> Vec<u8> {
    let rgba = object_rgba();
    let channel = |c: usize| rgba.as_slice().iter().map(|p| p[c]).collect::<Vec<f32>>();
    let mut channels = vec![
        ("R", f32s(&channel(0))),
        ("G", f32s(&channel(1))),
        ("B", f32s(&channel(2))),
        ("A", f32s(&channel(3))),
    ];
    if with_z {
        channels.push(("Z", f32s(object_range().as_slice())));
    }
    exr_bytes(W, H, vec![(None, channels)])
}

#[test]
fn a_blender_multilayer_object_is_read_with_its_alpha_and_depth() {
    let dir = tempfile::tempdir().unwrap();
    let rgba = object_rgba();
    let channel = |c: usize| rgba.as_slice().iter().map(|p| p[c]).collect::<Vec<f32>>();
    let bytes = exr_bytes(
        W,
        H,
        vec![(
            None,
            vec![
                ("ViewLayer.Combined.R", f32s(&channel(0))),
                ("ViewLayer.Combined.G", f32s(&channel(1))),
                ("ViewLayer.Combined.B", f32s(&channel(2))),
                ("ViewLayer.Combined.A", f32s(&channel(3))),
                ("ViewLayer.Depth.Z", f32s(object_range().as_slice())),
            ],
        )],
    );
    let path = dir.path().join("blender.exr");
    std::fs::write(&path, bytes).unwrap();
    let object = VirtualObject::load(&path, None, DepthKind::Range, None).unwrap();
    assert_eq!(object.rgba.as_slice(), rgba.as_slice());
    assert_eq!(*object.range.get(20, 10), OBJECT_M);
    assert!(object.range.get(0, 0).is_nan(), "no object: unknown range");
    // Depth along the axis without the camera's focal length: told what to give.
    let e = VirtualObject::load(&path, None, DepthKind::Depth, None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("`focal`") && e.contains("`fov`"), "{e}");
}

/// Writes the photo (linear EXR colour, range EXR in metres) and the object into `dir`.
fn write_inputs(dir: &std::path::Path, with_z: bool) {
    let image = photo_image();
    let channel = |c: usize| image.as_slice().iter().map(|p| p[c]).collect::<Vec<f32>>();
    let photo = exr_bytes(
        W,
        H,
        vec![(
            None,
            vec![
                ("R", f32s(&channel(0))),
                ("G", f32s(&channel(1))),
                ("B", f32s(&channel(2))),
            ],
        )],
    );
    std::fs::write(dir.join("photo.exr"), photo).unwrap();
    let range = exr_bytes(
        W,
        H,
        vec![(None, vec![("Z", f32s(photo_range().as_slice()))])],
    );
    std::fs::write(dir.join("range.exr"), range).unwrap();
    std::fs::write(dir.join("object.exr"), object_exr(with_z)).unwrap();
}

const RENDER: &[&str] = &[
    "render",
    "--image",
    "photo.exr",
    "--depth",
    "range.exr",
    "--depth-kind",
    "range",
    "--depth-scale",
    "1",
    "--beta",
    "0.08",
    "--lambda",
    "0",
    "--airlight",
    "0.7,0.75,0.8",
    "--no-prep",
    "--insert",
    "object.exr",
    "--insert-depth-kind",
    "range",
    "--out",
    "out.exr",
    "--json",
];

#[test]
fn cli_inserts_and_fogs_an_exr_object() {
    let dir = tempfile::tempdir().unwrap();
    write_inputs(dir.path(), true);
    let o = common::brume(dir.path(), RENDER);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(json["insert"]["pixels_in_front"], 8 * 12);
    assert_eq!(json["insert"]["pixels_partial"], 2 * 12);
    assert_eq!(json["insert"]["pixels_hidden"], 8 * 12);
    let out = brume::io::image::load_linear_rgb(&dir.path().join("out.exr")).unwrap();
    for (x, y) in [(20, 10), (10, 10), (28, 10), (25, 10), (24, 10), (2, 2)] {
        let (j, r) = expected_composite(x, y);
        let tau = (-BETA * f64::from(r)).exp() as f32;
        for k in 0..3 {
            let expected = tau * j[k] + (1.0 - tau) * AIRLIGHT[k];
            let got = out.get(x, y)[k];
            assert!(
                (got - expected).abs() < 2e-4,
                "({x}, {y}): {got} vs {expected}"
            );
        }
    }
}

#[test]
fn cli_reports_the_object_of_an_aerial_render() {
    let dir = tempfile::tempdir().unwrap();
    write_inputs(dir.path(), true);
    let beta = RENDER.iter().position(|&a| a == "--beta").unwrap();
    let mut args: Vec<&str> = [&RENDER[..beta], &RENDER[beta + 6..]].concat();
    args.extend(["--medium", "aerial", "--turbidity", "3", "--fov", "40"]);
    let o = common::brume(dir.path(), &args);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(json["medium"], "aerial");
    assert_eq!(json["insert"]["pixels_in_front"], 8 * 12);
    assert_eq!(json["insert"]["pixels_hidden"], 8 * 12);
}

#[test]
fn cli_takes_the_depth_from_a_separate_file_and_refuses_bad_objects() {
    let dir = tempfile::tempdir().unwrap();
    write_inputs(dir.path(), false);
    // No depth channel and no --insert-depth: told to give one.
    let o = common::brume(dir.path(), RENDER);
    assert!(!o.status.success());
    let e = common::stderr(&o);
    assert!(
        e.contains("object.exr") && e.contains("--insert-depth"),
        "{e}"
    );
    // The depth as its own file.
    let z = exr_bytes(
        W,
        H,
        vec![(None, vec![("Z", f32s(object_range().as_slice()))])],
    );
    std::fs::write(dir.path().join("object_z.exr"), z).unwrap();
    let mut args = RENDER.to_vec();
    args.extend(["--insert-depth", "object_z.exr"]);
    let o = common::brume(dir.path(), &args);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(json["insert"]["pixels_in_front"], 8 * 12);
    // An object of another size: both sizes named.
    let small = exr_bytes(
        4,
        4,
        vec![(
            None,
            vec![
                ("R", f32s(&[0.0; 16])),
                ("G", f32s(&[0.0; 16])),
                ("B", f32s(&[0.0; 16])),
                ("Z", f32s(&[1.0; 16])),
            ],
        )],
    );
    std::fs::write(dir.path().join("object.exr"), small).unwrap();
    let o = common::brume(dir.path(), RENDER);
    assert!(!o.status.success());
    let e = common::stderr(&o);
    assert!(e.contains("4x4") && e.contains("32x24"), "{e}");
}

/// The ego vehicle's hood (range 0 after pre-processing) is nearer than any object: an
/// object drawn over it stays hidden, and the rest of it shows as before.
#[test]
fn the_hood_hides_the_object() {
    let object = VirtualObject::from_range(object_rgba(), object_range(), "square").unwrap();
    let hood = |_: usize, y: usize| y >= 14;
    let mut image = photo_image();
    let mut range = Grid::from_fn(W, H, |x, y| {
        if hood(x, y) {
            0.0
        } else {
            *photo_range().get(x, y)
        }
    });
    object.composite(&mut image, &mut range).unwrap();
    for y in 0..H {
        for x in 0..W {
            let (colour, r) = if hood(x, y) {
                (WALL, 0.0)
            } else {
                expected_composite(x, y)
            };
            assert_eq!(*image.get(x, y), colour, "({x}, {y})");
            assert_eq!(*range.get(x, y), r, "range at ({x}, {y})");
        }
    }
}

/// An object whose colour or coverage holds a NaN (a renderer's or compositor's fault)
/// is refused, naming the file, the pixel and the channel, and nothing is written: before,
/// the fog's blur spread the NaN over the whole frame and `brume render` wrote an image
/// of NaN with success. A negative colour (a sharp filter's ringing) is set to 0.
#[test]
fn an_object_with_nan_colour_or_coverage_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    write_inputs(dir.path(), true);
    let mut args = RENDER.to_vec();
    let lambda = args.iter().position(|a| *a == "--lambda").unwrap();
    args[lambda + 1] = "4";
    for (x, channel, name) in [(20, 0, "R"), (21, 3, "A")] {
        let mut rgba = object_rgba();
        rgba.get_mut(x, 10)[channel] = f32::NAN;
        let channel = |c: usize| rgba.as_slice().iter().map(|p| p[c]).collect::<Vec<f32>>();
        let channels = ["R", "G", "B", "A"]
            .iter()
            .enumerate()
            .map(|(c, n)| (*n, f32s(&channel(c))))
            .chain([("Z", f32s(object_range().as_slice()))])
            .collect();
        std::fs::write(
            dir.path().join("object.exr"),
            exr_bytes(W, H, vec![(None, channels)]),
        )
        .unwrap();
        let o = common::brume(dir.path(), &args);
        let err = common::stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{err}");
        let said = format!(
            "object.exr: object value NaN at pixel ({x}, 10) (x, y from the top left), \
             channel {name}; 1 value(s) are NaN or infinite in all"
        );
        assert!(err.contains(&said), "{err}");
        assert!(!dir.path().join("out.exr").exists());
    }

    let mut rgba = object_rgba();
    rgba.get_mut(20, 10)[1] = -0.25;
    let object = VirtualObject::from_range(rgba, object_range(), "ringing").unwrap();
    assert_eq!(object.rgba.get(20, 10)[1], 0.0);
    assert_eq!(object.rgba.get(20, 10)[0], RED[0]);
}
