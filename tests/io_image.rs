//! Colour image loading: sRGB curves, PNG/JPEG decoding, errors on bad files.

use std::path::Path;

use brume::io::image::{decode_linear_rgb, linear_to_srgb, load_linear_rgb, srgb_to_linear};
use brume::Error;

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
