//! Colour image loading: sRGB curves, PNG/JPEG decoding, the linear float images of
//! renderers and engines (OpenEXR with flat or layered channel names, colour PFM), errors
//! on bad files.

use std::path::Path;

use brume::io::image::{decode_linear_rgb, linear_to_srgb, load_linear_rgb, srgb_to_linear};
use brume::raster::RgbImage;
use brume::Error;

use crate::common;
use common::{exr_bytes, f16s, f32s};

#[test]
fn srgb_known_values() {
    assert_eq!(srgb_to_linear(0.0), 0.0);
    assert_eq!(srgb_to_linear(1.0), 1.0);
    // The two branches meet at 0.04045 -> 0.04045 / 12.92.
    assert!((srgb_to_linear(0.04045) - 0.04045 / 12.92).abs() < 1e-9);
    assert!((srgb_to_linear(0.5) - 0.214_041_14).abs() < 1e-6);
    assert_eq!(linear_to_srgb(0.0), 0.0);
    assert!((linear_to_srgb(1.0) - 1.0).abs() < 1e-6);
    assert!((linear_to_srgb(0.214_041_14) - 0.5).abs() < 1e-6);
    assert!((linear_to_srgb(0.0031308) - 0.0031308 * 12.92).abs() < 1e-7);
}

#[test]
fn srgb_round_trip() {
    for i in 0..=1000 {
        let v = i as f32 / 1000.0;
        assert!((linear_to_srgb(srgb_to_linear(v)) - v).abs() < 1e-5, "{v}");
        assert!((srgb_to_linear(linear_to_srgb(v)) - v).abs() < 1e-5, "{v}");
    }
}

fn save(path: &Path, bytes: &[u8], w: u32, h: u32, colour: image::ExtendedColorType) {
    image::save_buffer(path, bytes, w, h, colour).unwrap();
}

#[test]
fn png_8bit_rgba_is_linearised_and_alpha_dropped() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("c.png");
    let px = [0u8, 128, 255, 10, 255, 0, 64, 255];
    save(&path, &px, 2, 1, image::ExtendedColorType::Rgba8);
    let img = load_linear_rgb(&path).unwrap();
    assert_eq!((img.width(), img.height()), (2, 1));
    let expect = |v: u8| srgb_to_linear(v as f32 / 255.0);
    assert_eq!(*img.get(0, 0), [expect(0), expect(128), expect(255)]);
    assert_eq!(*img.get(1, 0), [expect(255), expect(0), expect(64)]);
}

#[test]
fn png_16bit_grey_is_replicated_to_rgb() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("g16.png");
    let values: [u16; 2] = [0, 32768];
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_ne_bytes()).collect();
    save(&path, &bytes, 1, 2, image::ExtendedColorType::L16);
    let img = load_linear_rgb(&path).unwrap();
    assert_eq!(*img.get(0, 0), [0.0; 3]);
    let v = srgb_to_linear(32768.0 / 65535.0);
    for c in img.get(0, 1) {
        assert!((c - v).abs() < 1e-6);
    }
}

#[test]
fn jpeg_decodes() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("flat.jpg");
    let px = vec![200u8; 16 * 16 * 3];
    save(&path, &px, 16, 16, image::ExtendedColorType::Rgb8);
    let img = load_linear_rgb(&path).unwrap();
    assert_eq!((img.width(), img.height()), (16, 16));
    let want = srgb_to_linear(200.0 / 255.0);
    assert!((img.get(8, 8)[1] - want).abs() < 0.02);
}

/// Expects an error without printing the (large) image if there is none.
fn expect_err<T>(r: brume::Result<T>) -> Error {
    match r {
        Ok(_) => panic!("expected an error, got an image"),
        Err(e) => e,
    }
}

fn assert_format_error_naming(err: Error, name: &str) {
    let msg = err.to_string();
    assert!(matches!(err, Error::Format { .. }), "{msg}");
    assert!(msg.contains(name), "{msg} should name {name}");
}

#[test]
fn truncated_png_and_jpeg_are_errors_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    for (name, colour) in [
        ("t.png", image::ExtendedColorType::Rgb8),
        ("t.jpg", image::ExtendedColorType::Rgb8),
    ] {
        let full = dir.path().join(format!("full-{name}"));
        let px: Vec<u8> = (0..64 * 64 * 3).map(|i| (i * 7 % 251) as u8).collect();
        save(&full, &px, 64, 64, colour);
        let bytes = std::fs::read(&full).unwrap();
        let cut = dir.path().join(name);
        std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
        assert_format_error_naming(expect_err(load_linear_rgb(&cut)), name);
    }
}

/// A TIFF photo of a variant the decoder does not read (64-bit floats) is refused as such,
/// with what to do, not as "truncated or corrupt".
#[test]
fn an_unsupported_tiff_variant_is_named_not_called_corrupt() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("f64.tif");
    let mut tiff = tiff::encoder::TiffEncoder::new(std::fs::File::create(&path).unwrap()).unwrap();
    tiff.write_image::<tiff::encoder::colortype::RGB64Float>(2, 2, &[0.5; 12])
        .unwrap();
    let msg = expect_err(load_linear_rgb(&path)).to_string();
    for part in ["f64.tif", "64 bits", "32-bit float", "convert it"] {
        assert!(msg.contains(part), "{msg} should say {part}");
    }
    assert!(!msg.contains("corrupt"), "{msg}");
}

#[test]
fn jpeg_cut_anywhere_is_an_error_but_trailing_data_is_fine() {
    let dir = tempfile::tempdir().unwrap();
    let full = dir.path().join("full.jpg");
    let px: Vec<u8> = (0..48 * 40 * 3).map(|i| (i * 13 % 256) as u8).collect();
    save(&full, &px, 48, 40, image::ExtendedColorType::Rgb8);
    let bytes = std::fs::read(&full).unwrap();
    for cut in [
        4,
        bytes.len() / 4,
        bytes.len() * 3 / 4,
        bytes.len() - 2,
        bytes.len() - 1,
    ] {
        let err = expect_err(decode_linear_rgb(&bytes[..cut], "cut.jpg"));
        assert!(err.to_string().contains("cut.jpg"), "{err}");
    }
    // Cameras append data (maker notes, a second image) after the end marker.
    let mut trailer = bytes.clone();
    trailer.extend_from_slice(b"\xFF\xD8trailing maker data");
    assert!(decode_linear_rgb(&trailer, "trailer.jpg").is_ok());
}

#[test]
fn garbage_and_empty_bytes_are_errors() {
    assert_format_error_naming(
        expect_err(decode_linear_rgb(b"not an image", "x.png")),
        "x.png",
    );
    assert_format_error_naming(expect_err(decode_linear_rgb(b"", "empty.jpg")), "empty.jpg");
}

#[test]
fn missing_file_is_an_io_error() {
    let err = expect_err(load_linear_rgb(Path::new("/nonexistent/brume.png")));
    assert!(matches!(err, Error::Io { .. }));
    assert!(err.to_string().contains("/nonexistent/brume.png"));
}

/// A 3x2 frame's red, green and blue planes (top row first): HDR values above 1 included,
/// all exact in half floats too.
const RED: [f32; 6] = [0.0, 0.25, 1.0, 3.5, 1000.0, 0.125];
const GREEN: [f32; 6] = [0.5, 0.75, 2.0, 0.0, 8.0, 0.0625];
const BLUE: [f32; 6] = [1.5, 0.0, 0.5, 16.0, 0.25, 64.0];

fn write(dir: &Path, name: &str, bytes: &[u8]) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// Asserts a 3x2 image holding exactly `RED`, `GREEN`, `BLUE`.
fn assert_planes(img: &RgbImage) {
    assert_eq!((img.width(), img.height()), (3, 2));
    for i in 0..6 {
        assert_eq!(
            *img.get(i % 3, i / 3),
            [RED[i], GREEN[i], BLUE[i]],
            "pixel {i}"
        );
    }
}

#[test]
fn exr_rgb_is_linear_with_hdr_kept_and_alpha_and_depth_ignored() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = exr_bytes(
        3,
        2,
        vec![(
            None,
            vec![
                ("R", f32s(&RED)),
                ("G", f32s(&GREEN)),
                ("B", f32s(&BLUE)),
                ("A", f32s(&[0.5; 6])),
                ("Z", f32s(&[7.0; 6])),
            ],
        )],
    );
    let p = write(dir.path(), "frame.exr", &bytes);
    assert_planes(&load_linear_rgb(&p).unwrap());
    // The content decides, not the name.
    assert_planes(&decode_linear_rgb(&bytes, "frame.png").unwrap());
}

#[test]
fn blender_multilayer_exr_gives_the_combined_pass() {
    // Blender's names; `AO` sorts before `Combined` and `Vector` (motion, stored as RGBA)
    // after it, so neither "first layer" nor "last layer" would do.
    let ones = [1.0; 6];
    let bytes = exr_bytes(
        3,
        2,
        vec![(
            Some("ignored in a single-part file"),
            vec![
                ("ViewLayer.AO.R", f16s(&ones)),
                ("ViewLayer.AO.G", f16s(&ones)),
                ("ViewLayer.AO.B", f16s(&ones)),
                ("ViewLayer.Combined.R", f16s(&RED)),
                ("ViewLayer.Combined.G", f16s(&GREEN)),
                ("ViewLayer.Combined.B", f16s(&BLUE)),
                ("ViewLayer.Combined.A", f16s(&ones)),
                ("ViewLayer.Depth.Z", f32s(&[4.0; 6])),
                ("ViewLayer.Vector.R", f16s(&ones)),
                ("ViewLayer.Vector.G", f16s(&ones)),
                ("ViewLayer.Vector.B", f16s(&ones)),
                ("ViewLayer.Vector.A", f16s(&ones)),
            ],
        )],
    );
    assert_planes(&decode_linear_rgb(&bytes, "blender.exr").unwrap());

    // Without a Combined pass, the first layer with R, G and B.
    let bytes = exr_bytes(
        3,
        2,
        vec![(
            None,
            vec![
                ("beauty.R", f32s(&RED)),
                ("beauty.G", f32s(&GREEN)),
                ("beauty.B", f32s(&BLUE)),
                ("normals.R", f32s(&ones)),
                ("normals.G", f32s(&ones)),
                ("normals.B", f32s(&ones)),
                ("zz.R", f32s(&ones)),
            ],
        )],
    );
    assert_planes(&decode_linear_rgb(&bytes, "layers.exr").unwrap());
}

#[test]
fn multi_part_exr_reads_the_part_chosen() {
    // Both parts have channels R, G and B: the decoder alone would take the first.
    let nines = [9.0; 6];
    let bytes = exr_bytes(
        3,
        2,
        vec![
            (
                Some("ViewLayer.AO"),
                vec![
                    ("R", f32s(&nines)),
                    ("G", f32s(&nines)),
                    ("B", f32s(&nines)),
                ],
            ),
            (
                Some("ViewLayer.Combined"),
                vec![("B", f32s(&BLUE)), ("G", f32s(&GREEN)), ("R", f32s(&RED))],
            ),
        ],
    );
    assert_planes(&decode_linear_rgb(&bytes, "parts.exr").unwrap());
}

#[test]
fn grey_y_exr_is_replicated_and_depth_only_exr_is_refused() {
    let bytes = exr_bytes(3, 2, vec![(None, vec![("Y", f32s(&RED))])]);
    let img = decode_linear_rgb(&bytes, "grey.exr").unwrap();
    for (i, red) in RED.into_iter().enumerate() {
        assert_eq!(*img.get(i % 3, i / 3), [red; 3]);
    }
    // A depth map given as the colour image: refused, not shown as grey.
    for (file, channel) in [("z.exr", "Z"), ("blender-z.exr", "ViewLayer.Depth.Z")] {
        let bytes = exr_bytes(3, 2, vec![(None, vec![(channel, f32s(&[2.0; 6]))])]);
        let msg = expect_err(decode_linear_rgb(&bytes, file)).to_string();
        for needle in [file, channel, "R, G and B", "no colour"] {
            assert!(msg.contains(needle), "`{msg}` should mention `{needle}`");
        }
    }
    // Luminance-chroma: the chroma is not silently dropped.
    let bytes = exr_bytes(
        3,
        2,
        vec![(
            None,
            vec![("Y", f32s(&RED)), ("RY", f32s(&RED)), ("BY", f32s(&RED))],
        )],
    );
    let msg = expect_err(decode_linear_rgb(&bytes, "yc.exr")).to_string();
    assert!(msg.contains("luminance-chroma"), "{msg}");
}

#[test]
fn colour_pfm_is_linear_and_bottom_row_first() {
    // Rows bottom to top, little-endian (negative scale); the same image big-endian.
    for (little, scale) in [(true, "-1.0"), (false, "1.0")] {
        let mut bytes = format!("PF\n3 2\n{scale}\n").into_bytes();
        for y in [1, 0] {
            for x in 0..3 {
                let i = y * 3 + x;
                for v in [RED[i], GREEN[i], BLUE[i]] {
                    bytes.extend(if little {
                        v.to_le_bytes()
                    } else {
                        v.to_be_bytes()
                    });
                }
            }
        }
        assert_planes(&decode_linear_rgb(&bytes, "frame.pfm").unwrap());
    }
    let grey = [&b"Pf\n1 1\n-1\n"[..], &1.0f32.to_le_bytes()].concat();
    let msg = expect_err(decode_linear_rgb(&grey, "disp0.pfm")).to_string();
    assert!(msg.contains("disp0.pfm") && msg.contains("`PF`"), "{msg}");
}

#[test]
fn nan_is_refused_at_its_pixel_and_negatives_become_zero() {
    let mut red = RED;
    red[4] = f32::NAN; // pixel (1, 1)
    let mut blue = BLUE;
    blue[5] = f32::INFINITY;
    let bytes = exr_bytes(
        3,
        2,
        vec![(
            None,
            vec![("R", f32s(&red)), ("G", f32s(&GREEN)), ("B", f32s(&blue))],
        )],
    );
    let err = expect_err(decode_linear_rgb(&bytes, "nan.exr"));
    assert!(matches!(err, Error::Format { .. }));
    let msg = err.to_string();
    for needle in ["nan.exr", "(1, 1)", "channel R", "2 value(s)"] {
        assert!(msg.contains(needle), "`{msg}` should mention `{needle}`");
    }

    let mut green = GREEN;
    green[0] = -0.5;
    let bytes = exr_bytes(
        3,
        2,
        vec![(
            None,
            vec![("R", f32s(&RED)), ("G", f32s(&green)), ("B", f32s(&BLUE))],
        )],
    );
    let img = decode_linear_rgb(&bytes, "negative.exr").unwrap();
    assert_eq!(*img.get(0, 0), [RED[0], 0.0, BLUE[0]]);
    assert_eq!(*img.get(2, 1), [RED[5], GREEN[5], BLUE[5]]);
}

#[test]
fn truncated_or_corrupt_float_images_are_format_errors_naming_the_file() {
    let channels = |v: &[f32]| vec![(None, vec![("R", f32s(v)), ("G", f32s(v)), ("B", f32s(v))])];
    let values: Vec<f32> = (0..64 * 48).map(|i| (i % 97) as f32 * 0.37).collect();
    let exr = exr_bytes(64, 48, channels(&values));
    assert!(decode_linear_rgb(&exr, "whole.exr").is_ok());
    for cut in [5, 40, exr.len() / 3, exr.len() / 2, exr.len() - 1] {
        assert_format_error_naming(
            expect_err(decode_linear_rgb(&exr[..cut], "cut.exr")),
            "cut.exr",
        );
    }
    // ZIP streams overwritten with garbage, the header and offsets left intact.
    let mut corrupt = exr.clone();
    let from = corrupt.len() / 2;
    for (i, b) in corrupt[from..].iter_mut().enumerate() {
        *b = (i * 31 % 251) as u8;
    }
    assert_format_error_naming(
        expect_err(decode_linear_rgb(&corrupt, "bad.exr")),
        "bad.exr",
    );

    // A feature flag the reader does not know is a feature it lacks, not damage.
    let mut newer = exr.clone();
    newer[5] |= 0x20;
    let msg = expect_err(decode_linear_rgb(&newer, "newer.exr")).to_string();
    assert!(msg.contains("feature is not read"), "{msg}");
    assert!(!msg.contains("corrupt"), "{msg}");

    let pfm = [&b"PF\n2 2\n-1\n"[..], &[0u8; 4 * 3 * 3]].concat();
    assert_format_error_naming(expect_err(decode_linear_rgb(&pfm, "cut.pfm")), "cut.pfm");
    assert_format_error_naming(
        expect_err(decode_linear_rgb(b"PF", "magic.pfm")),
        "magic.pfm",
    );
    // Unknown data lists what is read.
    let msg = expect_err(decode_linear_rgb(b"GIF89a....", "x.gif")).to_string();
    for needle in ["x.gif", "PNG", "JPEG", "OpenEXR", "PFM"] {
        assert!(msg.contains(needle), "`{msg}` should mention `{needle}`");
    }
}

/// The first bytes of a HEIF file of major brand `brand`: an `ftyp` box of 24 bytes.
fn heif_head(brand: &[u8; 4]) -> Vec<u8> {
    let mut b = vec![0, 0, 0, 24];
    b.extend_from_slice(b"ftyp");
    b.extend_from_slice(brand);
    b.extend_from_slice(&[0, 0, 0, 0]);
    b.extend_from_slice(b"mif1heic");
    b.extend_from_slice(&[0; 64]);
    b
}

/// An iPhone's HEIC photo (or an AVIF) is refused with what to do instead, as an image,
/// as a depth file and as `render --image` alone; other ISO media (an MP4) is not taken
/// for one.
#[test]
fn heif_photos_are_refused_with_what_to_do() {
    for brand in [b"heic", b"heix", b"mif1"] {
        let bytes = heif_head(brand);
        let err = decode_linear_rgb(&bytes, "IMG_0001.HEIC")
            .unwrap_err()
            .to_string();
        let brand = std::str::from_utf8(brand).unwrap();
        for needle in [
            "IMG_0001.HEIC",
            "HEIF",
            brand,
            "Most Compatible",
            "heif-convert",
        ] {
            assert!(err.contains(needle), "`{err}` should mention `{needle}`");
        }
    }
    let err = decode_linear_rgb(&heif_head(b"avif"), "a.avif")
        .unwrap_err()
        .to_string();
    assert!(err.contains("AVIF") && err.contains("PNG or JPEG"), "{err}");
    let mp4 = heif_head(b"isom");
    let err = decode_linear_rgb(&mp4, "clip.mp4").unwrap_err().to_string();
    assert!(
        !err.contains("HEIF") && err.contains("unrecognised"),
        "{err}"
    );

    let dir = tempfile::tempdir().unwrap();
    let heic = dir.path().join("IMG_0001.HEIC");
    std::fs::write(&heic, heif_head(b"heic")).unwrap();
    let opts = brume::io::depth::DepthOptions::default();
    let err = brume::io::depth::load_range(&heic, &opts).unwrap_err();
    assert!(err.to_string().contains("Most Compatible"), "{err}");
    let run = common::brume(
        dir.path(),
        &["render", "--image", "IMG_0001.HEIC", "--out", "o.png"],
    );
    let log = common::stderr(&run);
    assert_eq!(run.status.code(), Some(1), "{log}");
    assert!(
        log.contains("HEIF") && !log.contains("--depth = (missing)"),
        "{log}"
    );
    common::assert_render_refuses("--depth", &heic, &["IMG_0001.HEIC", "HEIF"]);
}

/// The size a render checks its memory by, before decoding, and the size a host's photo
/// gives its depth map (`PhotoGeometry::read`), are those of the image the decoder reads:
/// for an EXR, the part and layer it chooses, read from the headers alone; for a PFM, its
/// header. A grey PFM is refused there as the decoder refuses it.
#[test]
fn float_images_give_their_size_from_their_headers() {
    use brume::io::depth::PhotoGeometry;
    use brume::io::image::image_dimensions;
    use common::exr_sized_parts_bytes;
    let dir = tempfile::tempdir().unwrap();
    let ones = [1.0; 20];
    // The chosen part (Combined) is 3x2; the one before it 5x4.
    let exr = exr_sized_parts_bytes(vec![
        (
            (5, 4),
            (
                Some("ViewLayer.AO"),
                vec![("R", f32s(&ones)), ("G", f32s(&ones)), ("B", f32s(&ones))],
            ),
        ),
        (
            (3, 2),
            (
                Some("ViewLayer.Combined"),
                vec![("B", f32s(&BLUE)), ("G", f32s(&GREEN)), ("R", f32s(&RED))],
            ),
        ),
    ]);
    assert_planes(&decode_linear_rgb(&exr, "parts.exr").unwrap());
    let grey = exr_sized_parts_bytes(vec![((4, 7), (None, vec![("Y", f32s(&[0.5; 28]))]))]);
    // A PFM's header only: the data is not looked at.
    let pfm = b"PF\n6000 4000\n-1.0\n".to_vec();
    for (name, bytes, size) in [
        ("parts.exr", &exr, (3, 2)),
        ("grey.exr", &grey, (4, 7)),
        ("frame.pfm", &pfm, (6000, 4000)),
    ] {
        assert_eq!(image_dimensions(bytes, name).unwrap(), size, "{name}");
        let geometry = PhotoGeometry::read(&write(dir.path(), name, bytes)).unwrap();
        let size = (size.0 as usize, size.1 as usize);
        assert_eq!((geometry.width, geometry.height), size, "{name}");
        assert_eq!(geometry.exif, Default::default(), "{name}");
    }
    let depth_only = exr_sized_parts_bytes(vec![((3, 2), (None, vec![("Z", f32s(&[2.0; 6]))]))]);
    let grey_pfm = b"Pf\n3 2\n-1\n".to_vec();
    for (name, bytes, needle) in [
        ("z.exr", &depth_only, "no colour"),
        ("d.pfm", &grey_pfm, "`PF`"),
    ] {
        let msg = expect_err(image_dimensions(bytes, name)).to_string();
        assert!(msg.contains(name) && msg.contains(needle), "{msg}");
    }
}
