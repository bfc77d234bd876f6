//! A photo's EXIF orientation: a phone held upright stores its sensor's frame sideways
//! with a tag that viewers apply, and writes its depth (DEPTH16, GDepth, Dynamic Depth) as
//! the photo is stored. brume turns the photo upright and the depth map with it, so that
//! the sky, the horizon and the output are the upright photo's: a tagged pair fogs
//! exactly as the upright pair does.

use std::path::Path;

use brume::io::depth::{load_range, DepthKind, DepthOptions};
use brume::io::image::{decode_upright_rgb, linear_to_srgb8};
use brume::io::output::write_scalar;
use brume::photo::Photo;
use brume::prep::synthetic::street_scene;
use brume::raster::{Grid, Orientation, ScalarMap};
use image::ImageEncoder;

use crate::common;

const W: usize = 128;
const H: usize = 80;

/// A little-endian EXIF (TIFF) block, written here by hand from the TIFF 6.0 and Exif 2.3
/// layouts: IFD0 holding orientation `value` and, with `focal_35mm`, a pointer to an Exif
/// IFD holding `FocalLengthIn35mmFilm` and, if given, the size the camera wrote
/// (`PixelXDimension`, `PixelYDimension`).
fn exif_block(value: u16, focal_35mm: Option<(u16, Option<(u32, u32)>)>) -> Vec<u8> {
    // An entry whose one value (SHORT, type 3, or LONG, 4) is held in it.
    let entry = |b: &mut Vec<u8>, tag: u16, kind: u16, value: u32| {
        b.extend(tag.to_le_bytes());
        b.extend(kind.to_le_bytes());
        b.extend(1u32.to_le_bytes());
        match kind {
            3 => b.extend((value as u16).to_le_bytes().into_iter().chain([0, 0])),
            _ => b.extend(value.to_le_bytes()),
        }
    };
    let mut b = b"II*\0".to_vec();
    b.extend(8u32.to_le_bytes()); // the first IFD
    let entries = 1 + u16::from(focal_35mm.is_some());
    b.extend(entries.to_le_bytes());
    entry(&mut b, 0x0112, 3, u32::from(value)); // Orientation
    if focal_35mm.is_some() {
        // IFD0 ends at 8 + 2 + 12 per entry + 4: the Exif IFD follows.
        entry(&mut b, 0x8769, 4, 8 + 2 + 12 * 2 + 4);
    }
    b.extend(0u32.to_le_bytes()); // no next IFD
    if let Some((focal, written)) = focal_35mm {
        b.extend((1 + 2 * u16::from(written.is_some())).to_le_bytes());
        if let Some((w, h)) = written {
            entry(&mut b, 0xA002, 4, w); // PixelXDimension
            entry(&mut b, 0xA003, 4, h); // PixelYDimension
        }
        entry(&mut b, 0xA405, 3, u32::from(focal)); // FocalLengthIn35mmFilm
        b.extend(0u32.to_le_bytes());
    }
    b
}

/// A PNG of `pixels` carrying the EXIF block `exif`, if any.
fn png_bytes<const N: usize>(pixels: &Grid<[u8; N]>, exif: Option<Vec<u8>>) -> Vec<u8> {
    let mut bytes = Vec::new();
    let mut png = image::codecs::png::PngEncoder::new(&mut bytes);
    if let Some(exif) = exif {
        png.set_exif_metadata(exif).unwrap();
    }
    let colour = match N {
        1 => image::ExtendedColorType::L8,
        _ => image::ExtendedColorType::Rgb8,
    };
    let (w, h) = (pixels.width() as u32, pixels.height() as u32);
    png.write_image(pixels.as_slice().as_flattened(), w, h, colour)
        .unwrap();
    bytes
}

/// Writes 8-bit `pixels` (grey or RGB) as a PNG, with an EXIF orientation if given.
fn write_png<const N: usize>(path: &Path, pixels: &Grid<[u8; N]>, exif: Option<u16>) {
    let exif = exif.map(|value| exif_block(value, None));
    std::fs::write(path, png_bytes(pixels, exif)).unwrap();
}

/// The street frame upright: its 8-bit sRGB photo, its range (holes, sky unknown) and
/// its true sky as a binary mask.
fn street() -> (Grid<[u8; 3]>, ScalarMap, Grid<[u8; 1]>) {
    let s = street_scene(W, H, 7);
    let photo = s.image.map(|p| p.map(linear_to_srgb8));
    let sky = s.sky.map(|&sky| [if sky { 255 } else { 0 }]);
    (photo, s.range, sky)
}

/// What a camera stores for an upright grid under `orientation`: the grid that
/// `orientation` turns into `upright`.
fn stored<T: Clone + Send + Sync>(upright: &Grid<T>, orientation: Orientation) -> Grid<T> {
    upright.oriented(orientation.inverse())
}

fn orientation(exif: u16) -> Orientation {
    Orientation::from_exif(exif).unwrap()
}

/// Writes the street pair as stored under EXIF orientation `exif` (`None`: upright, no
/// tag) as `{name}.png`, `{name}.pfm` and `{name}-sky.png`. The mask carries the tag too,
/// as a phone's PNG may: a map's own tag is not read (the map follows its photo).
fn write_pair(dir: &Path, name: &str, exif: Option<u16>) {
    let (photo, range, sky) = street();
    let o = exif.map_or(Orientation::Upright, orientation);
    write_png(&dir.join(format!("{name}.png")), &stored(&photo, o), exif);
    write_scalar(&dir.join(format!("{name}.pfm")), &stored(&range, o)).unwrap();
    write_png(&dir.join(format!("{name}-sky.png")), &stored(&sky, o), exif);
}

/// `brume render` of `image` and `depth` in `dir` with `extra` options: the output's
/// size and 8-bit pixels, and the `--json` report.
fn render(dir: &Path, image: &str, depth: &str, extra: &[&str]) -> ((u32, u32), Vec<u8>, String) {
    let out = dir.join("out.png");
    let mut args = vec![
        "render", "--image", image, "--depth", depth, "--out", "out.png", "--json",
    ];
    args.extend(extra);
    let run = common::brume(dir, &args);
    assert!(run.status.success(), "{}", common::stderr(&run));
    let fogged = image::open(&out).unwrap().into_rgb8();
    std::fs::remove_file(&out).unwrap();
    let report = String::from_utf8(run.stdout).unwrap();
    (fogged.dimensions(), fogged.into_raw(), report)
}

#[test]
fn a_tagged_photo_and_its_stored_depth_fog_as_the_upright_pair() {
    let dir = tempfile::tempdir().unwrap();
    let dir = dir.path();
    write_pair(dir, "upright", None);
    let (size, reference, _) = render(dir, "upright.png", "upright.pfm", &[]);
    assert_eq!(size, (W as u32, H as u32));
    // Two that swap the axes (a phone held upright, or the other way), the upside-down
    // one, and a transpose.
    for exif in [6, 8, 3, 5] {
        let name = format!("exif{exif}");
        write_pair(dir, &name, Some(exif));
        let (image, depth) = (format!("{name}.png"), format!("{name}.pfm"));
        let (size, fogged, report) = render(dir, &image, &depth, &[]);
        assert_eq!(size, (W as u32, H as u32), "EXIF {exif}: the upright size");
        assert!(
            fogged == reference,
            "EXIF {exif}: not the upright pair's fog"
        );
        let turned = format!("{} with the photo", orientation(exif).describe());
        assert!(report.contains(&turned), "EXIF {exif}: {report}");
    }
}

/// The same stored pair with the tag left out: the fog of the sideways frame, turned
/// upright afterwards, is not the upright frame's (the sky and the horizon are looked for
/// at the top of the frame), which is what turning it first is for.
#[test]
fn without_its_tag_the_sideways_frame_fogs_otherwise() {
    let dir = tempfile::tempdir().unwrap();
    let dir = dir.path();
    write_pair(dir, "upright", None);
    let (_, reference, _) = render(dir, "upright.png", "upright.pfm", &[]);
    let (photo, range, _) = street();
    let o = orientation(6);
    write_png(&dir.join("sideways.png"), &stored(&photo, o), None);
    write_scalar(&dir.join("sideways.pfm"), &stored(&range, o)).unwrap();
    let (size, fogged, _) = render(dir, "sideways.png", "sideways.pfm", &[]);
    assert_eq!(size, (H as u32, W as u32), "as stored");
    let fogged = Grid::from_vec(H, W, fogged.chunks(3).map(|p| [p[0], p[1], p[2]]).collect());
    let turned = fogged.oriented(o);
    let differing = turned
        .as_slice()
        .iter()
        .zip(reference.chunks(3))
        .filter(|(a, b)| a.iter().zip(b.iter()).any(|(x, y)| x.abs_diff(*y) > 8))
        .count();
    assert!(
        differing > W * H / 20,
        "{differing} pixels differ by over 8 codes"
    );
}

#[test]
fn a_depth_map_upright_already_is_not_turned_again() {
    let dir = tempfile::tempdir().unwrap();
    let dir = dir.path();
    write_pair(dir, "upright", None);
    let (_, reference, _) = render(dir, "upright.png", "upright.pfm", &[]);
    // Turned by 90°, the shape tells: the upright map fits only the upright photo.
    write_pair(dir, "exif6", Some(6));
    let (_, fogged, report) = render(dir, "exif6.png", "upright.pfm", &[]);
    assert!(fogged == reference);
    assert!(report.contains("upright already (its shape is the upright photo's)"));
    // Turned by 180°, it cannot: --depth-layout says so, and without it the map is
    // taken as stored, turned, and the fog is another.
    write_pair(dir, "exif3", Some(3));
    let upright = ["--depth-layout", "upright"];
    let (_, fogged, report) = render(dir, "exif3.png", "upright.pfm", &upright);
    assert!(fogged == reference);
    assert!(
        report.contains("taken as upright (--depth-layout upright)"),
        "{report}"
    );
    let (_, fogged, _) = render(dir, "exif3.png", "upright.pfm", &[]);
    assert!(fogged != reference);
}

#[test]
fn a_sky_mask_is_turned_as_the_depth_map() {
    let dir = tempfile::tempdir().unwrap();
    let dir = dir.path();
    write_pair(dir, "upright", None);
    let mask = ["--sky-mask", "upright-sky.png"];
    let (_, reference, _) = render(dir, "upright.png", "upright.pfm", &mask);
    let (_, unmasked, _) = render(dir, "upright.png", "upright.pfm", &[]);
    assert!(reference != unmasked, "the mask changes the fog");
    for exif in [6, 3] {
        let name = format!("exif{exif}");
        write_pair(dir, &name, Some(exif));
        let (image, depth) = (format!("{name}.png"), format!("{name}.pfm"));
        // As stored (as the depth), and upright already (by its shape).
        let mut masks = vec![format!("{name}-sky.png")];
        if exif == 6 {
            masks.push("upright-sky.png".into());
        }
        for mask in masks {
            let (_, fogged, _) = render(dir, &image, &depth, &["--sky-mask", &mask]);
            assert!(fogged == reference, "EXIF {exif}, {mask}");
        }
    }
}

/// `prep --out` stands in for its `--depth`: laid out as it, whatever the photo's tag,
/// and the upright photo's prepared range once turned.
#[test]
fn prep_writes_its_range_as_the_depth_file_lies() {
    let dir = tempfile::tempdir().unwrap();
    let dir = dir.path();
    let prep = |image: &str, depth: &str| {
        let args = ["prep", "--image", image, "--depth", depth, "--out", "p.pfm"];
        let run = common::brume(dir, &args);
        assert!(run.status.success(), "{}", common::stderr(&run));
        match brume::io::depth::read_pfm(&dir.join("p.pfm")).unwrap() {
            brume::io::depth::Pfm::Grey(map) => map,
            _ => panic!("a one-channel PFM"),
        }
    };
    write_pair(dir, "upright", None);
    let reference = prep("upright.png", "upright.pfm");
    write_pair(dir, "exif6", Some(6));
    let prepared = prep("exif6.png", "exif6.pfm");
    assert_eq!((prepared.width(), prepared.height()), (H, W), "as stored");
    let bits = |m: &ScalarMap| m.as_slice().iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&prepared.oriented(orientation(6))), bits(&reference));
}

/// `fov` is the upright photo's vertical field of view: across the stored map's width
/// when the photo turns by 90°. Depth along the axis of a wall at 10 m becomes
/// R = Z·sqrt(1 + ((u − cx)/f)² + ((v − cy)/f)²) on the upright grid, f from its height.
#[test]
fn the_field_of_view_is_the_upright_photos() {
    let dir = tempfile::tempdir().unwrap();
    let (photo, _, _) = street();
    let o = orientation(6);
    write_png(&dir.path().join("p.png"), &stored(&photo, o), Some(6));
    let depth = dir.path().join("z.pfm");
    write_scalar(&depth, &Grid::filled(H, W, 10.0)).unwrap();
    let opts = DepthOptions {
        kind: Some(DepthKind::Depth),
        fov: Some(60.0),
        ..DepthOptions::default()
    };
    let loaded = Photo::load(&dir.path().join("p.png"), &depth, &opts).unwrap();
    let range = &loaded.depth.range;
    assert_eq!((range.width(), range.height()), (W, H));
    let f = H as f64 / 2.0 / 30f64.to_radians().tan();
    let (cx, cy) = ((W as f64 - 1.0) / 2.0, (H as f64 - 1.0) / 2.0);
    for (u, v) in [
        (0, 0),
        (W - 1, 0),
        (0, H - 1),
        (W / 2, H / 2),
        (W - 1, H - 1),
    ] {
        let (a, b) = ((u as f64 - cx) / f, (v as f64 - cy) / f);
        let want = 10.0 * (1.0 + a * a + b * b).sqrt();
        let got = f64::from(*range.get(u, v));
        assert!(
            (got - want).abs() < 1e-4 * want,
            "({u}, {v}): {got} for {want}"
        );
    }
}

fn gdepth(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/gdepth")
        .join(name)
}

/// `rot6.jpg` is `inv8.jpg` with an Orientation of 6 that ExifTool added: the photo and
/// its embedded depth come out turned 90° clockwise, each depth sample the stored one.
#[test]
fn a_portrait_photos_embedded_depth_turns_with_it() {
    let stored = load_range(&gdepth("inv8.jpg"), &DepthOptions::default()).unwrap();
    let (path, opts) = (gdepth("rot6.jpg"), DepthOptions::default());
    let photo = Photo::load(&path, &path, &opts).unwrap();
    assert_eq!((photo.image.width(), photo.image.height()), (48, 64));
    let range = &photo.depth.range;
    assert_eq!((range.width(), range.height()), (24, 32));
    assert_eq!(photo.depth.turned, Orientation::Rotate90);
    for v in 0..32 {
        for u in 0..24 {
            // Turned 90° clockwise: the upright top row is the stored left column, from
            // the bottom up.
            let want = stored.range.get(v, 23 - u);
            assert_eq!(range.get(u, v).to_bits(), want.to_bits(), "({u}, {v})");
        }
    }

    // Dynamic Depth's intrinsics turn too: the axes' focal lengths swap, and the stored
    // principal point's y, from the bottom, becomes the upright x.
    let k = load_range(&gdepth("dd8.jpg"), &opts)
        .unwrap()
        .intrinsics
        .unwrap();
    let path = gdepth("dd8-rot6.jpg");
    let turned = Photo::load(&path, &path, &opts).unwrap().depth;
    let t = turned.intrinsics.unwrap();
    assert_eq!((t.fx, t.fy, t.cx, t.cy), (k.fy, k.fx, 23.0 - k.cy, k.cx));

    // The render needs no --depth and writes the upright photo.
    let (dir, _) = render_fixture("rot6.jpg", &[]);
    let size = image::image_dimensions(dir.path().join("o.png")).unwrap();
    assert_eq!(size, (48, 64));
}

/// `f26.jpg` is `rot6.jpg` with a `FocalLengthIn35mmFormat` of 26 mm that ExifTool wrote:
/// its depth along the axis becomes range through the focal length that gives the
/// photo's diagonal the angle 26 mm gives a 36 x 24 mm frame's (43.27 mm), on the upright
/// grid; a `fov` given wins.
#[test]
fn the_photos_35mm_focal_length_turns_its_depth_into_range() {
    let opts = DepthOptions::default();
    let rot6 = gdepth("rot6.jpg");
    let depth = Photo::load(&rot6, &rot6, &opts).unwrap().depth;
    assert!(depth.depth_as_range_warning().is_some(), "no focal length");
    let path = gdepth("f26.jpg");
    let loaded = Photo::load(&path, &path, &opts).unwrap().depth;
    assert!(loaded.depth_as_range_warning().is_none());
    let note = loaded
        .notes
        .iter()
        .find(|n| n.contains("from the photo's EXIF"));
    assert!(
        note.is_some_and(|n| n.contains("26 mm")),
        "{:?}",
        loaded.notes
    );
    let check = |range: &ScalarMap, f: f64| {
        let (cx, cy) = (11.5, 15.5);
        for v in 0..32 {
            for u in 0..24 {
                let z = f64::from(*depth.range.get(u, v));
                let got = f64::from(*range.get(u, v));
                if z.is_nan() {
                    assert!(got.is_nan(), "({u}, {v})");
                    continue;
                }
                let (a, b) = ((u as f64 - cx) / f, (v as f64 - cy) / f);
                let want = z * (1.0 + a * a + b * b).sqrt();
                assert!(
                    (got - want).abs() < 1e-5 * want,
                    "({u}, {v}): {got} for {want}"
                );
            }
        }
    };
    // The map is 24 x 32 upright, 40 px across its diagonal.
    check(&loaded.range, 26.0 * 40.0 / 36f64.hypot(24.0));
    let fov = DepthOptions {
        fov: Some(50.0),
        ..DepthOptions::default()
    };
    let given = Photo::load(&path, &path, &fov).unwrap().depth;
    check(&given.range, 16.0 / 25f64.to_radians().tan());
}

/// `f26-crop.jpg` is `f26.jpg` whose EXIF says the camera wrote 4032 x 2268, 16:9, where
/// the photo is 4:3: cropped, its field of view is not the tag's, so the focal length is
/// not used (the depth is used as range, with the warning), and the same aspect ratio
/// (`f26.jpg` has none written) keeps it.
#[test]
fn a_cropped_photos_exif_focal_length_is_not_used() {
    let path = gdepth("f26-crop.jpg");
    let loaded = Photo::load(&path, &path, &DepthOptions::default()).unwrap();
    assert_eq!(loaded.exif.focal_35mm, None);
    assert_eq!(loaded.exif.orientation, Orientation::Rotate90);
    assert!(loaded.depth.depth_as_range_warning().is_some());
    let (_, run) = render_fixture("f26-crop.jpg", &[]);
    let err = common::stderr(&run);
    assert!(
        err.contains("its EXIF focal length (26 mm in 35 mm terms) is not used")
            && err.contains("the camera wrote 4032x2268"),
        "{err}"
    );
    let kept = Photo::load(
        &gdepth("f26.jpg"),
        &gdepth("f26.jpg"),
        &DepthOptions::default(),
    );
    assert_eq!(kept.unwrap().exif.focal_35mm, Some(26.0));
}

/// The focal length is kept where the camera wrote the same aspect ratio (resized, or
/// turned without the tags swapped: the diagonal's angle is the same), or wrote no size
/// (0 is "unknown"), and dropped where it wrote another (cropped).
#[test]
fn the_focal_length_of_a_photo_written_at_another_aspect_ratio_is_dropped() {
    let photo = Grid::filled(64, 48, [90u8, 120, 150]);
    let focal = |written| {
        let png = png_bytes(&photo, Some(exif_block(1, Some((26, written)))));
        let exif = decode_upright_rgb(&png, "p.png").unwrap().exif;
        exif.focal_35mm
    };
    assert_eq!(focal(None), Some(26.0));
    assert_eq!(focal(Some((4032, 3024))), Some(26.0), "resized");
    assert_eq!(focal(Some((3024, 4032))), Some(26.0), "turned");
    assert_eq!(focal(Some((0, 0))), Some(26.0), "unknown");
    assert_eq!(focal(Some((4032, 2268))), None, "16:9 of 4:3");
    assert_eq!(focal(Some((4032, 3072))), None, "1.6 % off");
}

/// `brume render --image` of the fixture `name` with `extra` options, written to `o.png`
/// in a new directory (returned with the run, which succeeded).
fn render_fixture(name: &str, extra: &[&str]) -> (tempfile::TempDir, std::process::Output) {
    let dir = tempfile::tempdir().unwrap();
    let image = gdepth(name);
    let mut args = vec!["render", "--image", image.to_str().unwrap()];
    args.extend(extra);
    args.extend(["--out", "o.png"]);
    let run = common::brume(dir.path(), &args);
    assert!(run.status.success(), "{}", common::stderr(&run));
    (dir, run)
}

/// The field of view `brume render --medium aerial` gives its camera for `f26.jpg` as its
/// own depth, with `extra` depth options (`--json`'s `fov`).
fn aerial_fov(extra: &[&str]) -> f64 {
    let image = gdepth("f26.jpg");
    let mut args = vec!["--depth", image.to_str().unwrap()];
    args.extend(extra);
    args.extend(["--medium", "aerial", "--turbidity", "3", "--json"]);
    let (_, run) = render_fixture("f26.jpg", &args);
    let report: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
    report["fov"].as_f64().unwrap()
}

/// The aerial perspective's camera takes the field of view the EXIF gives: the depth's
/// focal length is in the map's pixels (24 x 32, upright), the camera's in the photo's
/// (48 x 64), so the field is the photo's 2·atan(64 / 2 / (2 f)), not twice as wide.
#[test]
fn the_aerial_camera_takes_the_exif_field_of_view_at_the_photos_size() {
    let focal = 2.0 * 26.0 * 40.0 / 36f64.hypot(24.0);
    let want = 2.0 * (32.0 / focal).atan().to_degrees();
    let fov = aerial_fov(&[]);
    assert!((fov - want).abs() < 1e-6, "{fov} for {want}");
}

/// A map of range needs no focal length, but the aerial perspective's camera does: it
/// takes the photo's EXIF one at the photo's size (f26.jpg read as range: no intrinsics
/// from the depth), 26 · 80 / 43.27 px over its 64 rows.
#[test]
fn the_aerial_camera_takes_the_exif_focal_length_beside_a_map_of_range() {
    let focal = 26.0 * 80.0 / 36f64.hypot(24.0);
    let want = 2.0 * (32.0 / focal).atan().to_degrees();
    let fov = aerial_fov(&["--depth-kind", "range"]);
    assert!((fov - want).abs() < 1e-6, "{fov} for {want}");
}
