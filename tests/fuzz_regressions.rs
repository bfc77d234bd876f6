//! Inputs the fuzzers in `fuzz/` found crashing a loader, kept as files in
//! `tests/data/fuzz/` and replayed on stable Rust: each must now give its expected result
//! without a panic or an abort; also inputs of the same kind found by reading the code.
//! Also checks that the fuzzers' seeds in `fuzz/seeds/` are files the loaders accept, so
//! that fuzzing starts from inputs that reach deep into each decoder.

use std::path::{Path, PathBuf};

use brume::io::depth::{load_range, DepthOptions};
use brume::io::image::load_linear_rgb;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn files(dir: &str) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(root().join(dir))
        .unwrap_or_else(|e| panic!("{dir}: {e}"))
        .map(|e| e.unwrap().path())
        .collect();
    v.sort();
    v
}

#[test]
fn seeds_of_the_single_format_fuzzers_load() {
    let mut checked = 0;
    for target in ["pfm", "exr", "tiff", "npy", "npz"] {
        for path in files(&format!("fuzz/seeds/{target}")) {
            let name = path.file_name().unwrap().to_string_lossy();
            // Kept on purpose to reach the refusals: colour PFM, integer TIFF and .npy.
            if ["rgb.pfm", "u16.tif", "int.npy"].contains(&name.as_ref()) {
                assert!(
                    load_range(&path, &DepthOptions::default()).is_err(),
                    "{name}"
                );
                continue;
            }
            let loaded = load_range(&path, &DepthOptions::default());
            assert!(loaded.is_ok(), "{}: {:?}", path.display(), loaded.err());
            checked += 1;
        }
    }
    for path in files("fuzz/seeds/colour_image") {
        // Kept on purpose to reach the refusal of an HDR PNG.
        let refused = path.ends_with("icc-cicp-pq-flat.png");
        assert_eq!(
            load_linear_rgb(&path).is_err(),
            refused,
            "{}",
            path.display()
        );
        checked += 1;
    }
    assert!(checked >= 15, "only {checked} seeds");
}

#[test]
fn seeds_of_the_camera_manifest_and_sky_mask_fuzzers_load() {
    use brume::io::mask::{decode_sky_mask, SkyMaskFormat};

    let cameras = files("fuzz/seeds/camera");
    for path in &cameras {
        let parsed = brume::io::depth::parse_camera(path);
        assert!(parsed.is_ok(), "{}: {:?}", path.display(), parsed.err());
    }
    let manifests = files("fuzz/seeds/manifest");
    for path in &manifests {
        let items = brume::dataset::read_manifest(path);
        assert!(
            items.as_ref().is_ok_and(|v| !v.is_empty()),
            "{}: {:?}",
            path.display(),
            items.err()
        );
    }
    // Byte 0 picks the format, as in fuzz/fuzz_targets/sky_mask.rs; the rest is the PNG.
    let masks = files("fuzz/seeds/sky_mask");
    for path in &masks {
        let bytes = std::fs::read(path).unwrap();
        let format = SkyMaskFormat::ALL[usize::from(bytes[0]) % SkyMaskFormat::ALL.len()];
        let name = path.display().to_string();
        let mask = decode_sky_mask(&bytes[1..], &name, format);
        assert!(mask.is_ok(), "{name} as {format}: {:?}", mask.err());
        let mask = mask.unwrap();
        assert!(mask.as_slice().iter().any(|&sky| sky), "{name}: no sky");
        assert!(!mask.as_slice().iter().all(|&sky| sky), "{name}: all sky");
    }
    let counts = [cameras.len(), manifests.len(), masks.len()];
    assert!(counts.iter().all(|&n| n >= 4), "seeds: {counts:?}");
}

#[test]
fn seeds_of_the_transmittance_map_table_and_time_fuzzers_load() {
    use brume::atmosphere::Sensitivity;
    use brume::medium::DensityTable;

    let maps = files("fuzz/seeds/transmittance_map");
    for path in &maps {
        let loaded = brume::compat::load_optical_depth(path);
        // Kept on purpose to reach the refusal after decoding: a palette of colours.
        if path.ends_with("palette.png") {
            expect_err_with(loaded, "an RGB transmittance map whose channels differ");
            continue;
        }
        let map = loaded.unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(map.as_slice().iter().all(|&v| v.is_finite() && v > 0.0));
    }
    // Byte 0 picks the table, as in fuzz/fuzz_targets/tables.rs; the rest is the CSV.
    let tables = files("fuzz/seeds/tables");
    for path in &tables {
        let bytes = std::fs::read(path).unwrap();
        let text = std::str::from_utf8(&bytes[1..]).unwrap();
        let ok = match bytes[0] % 2 {
            0 => DensityTable::parse_csv(text, path).err(),
            _ => Sensitivity::parse_csv(text, path).err(),
        };
        assert!(ok.is_none(), "{}: {ok:?}", path.display());
    }
    let times = files("fuzz/seeds/sun_time");
    for path in &times {
        let text = std::fs::read_to_string(path).unwrap();
        let sun = brume::sky::sun_position::Observer::new(47.4, 8.5).sun_at(&text, None);
        assert!(sun.is_ok(), "{}: {:?}", path.display(), sun.err());
    }
    let counts = [maps.len(), tables.len(), times.len()];
    assert!(counts.iter().all(|&n| n >= 4), "seeds: {counts:?}");
}

fn fuzz_file(name: &str) -> PathBuf {
    root().join("tests/data/fuzz").join(name)
}

/// Runs `load` and says how long it took, for inputs that used to run for seconds.
fn timed<T>(load: impl FnOnce() -> T) -> (T, std::time::Duration) {
    let start = std::time::Instant::now();
    let out = load();
    (out, start.elapsed())
}

fn expect_err_with(r: brume::Result<impl Sized>, needle: &str) {
    match r {
        Ok(_) => panic!("expected an error mentioning `{needle}`"),
        Err(e) => assert!(
            e.to_string().contains(needle),
            "`{e}` should mention `{needle}`"
        ),
    }
}

// npy fuzzer, 43 527 runs in: a header of 16 `{` and stray quotes made the Python-literal
// parser that npyz uses (and that the first shape check borrowed) backtrack for longer
// than the 10 s timeout; each further `{` triples the time.
#[test]
fn npy_header_of_nested_braces_is_refused_at_once() {
    let path = fuzz_file("npy-nested-braces-timeout.npy");
    let (r, took) = timed(|| load_range(&path, &DepthOptions::default()));
    expect_err_with(r, "not the dictionary numpy writes");
    assert!(took.as_secs_f64() < 1.0, "took {took:?}");
    // The file says version 1.48, which npyz refuses before parsing; as 1.0 it would
    // reach npyz's parser.
    let mut bytes = std::fs::read(&path).unwrap();
    bytes[7] = 0;
    let dir = tempfile::tempdir().unwrap();
    let v10 = dir.path().join("v10.npy");
    std::fs::write(&v10, bytes).unwrap();
    let (r, took) = timed(|| load_range(&v10, &DepthOptions::default()));
    expect_err_with(r, "not the dictionary numpy writes");
    assert!(took.as_secs_f64() < 1.0, "took {took:?}");
}

// npy fuzzer, second run, 7.3 million runs in: shape (2, 3, 13332233333333333333), a
// 3-D shape the first check let through for npyz to refuse, overflowed npyz's product of
// the dimensions (a panic with overflow checks on).
#[test]
fn npy_three_dimensional_shape_that_overflows_is_refused() {
    let path = fuzz_file("npy-3d-shape-overflow.npy");
    expect_err_with(
        load_range(&path, &DepthOptions::default()),
        "expected (height, width)",
    );
}

// colour_image fuzzer, about 2 million runs in: a 1192-byte JPEG claiming 10280x10280
// decoded for 10 s into 1.9 GB of grey. Now beyond MAX_PIXELS; at 8192x8192, within it,
// the file is refused as too short for its size.
#[test]
fn tiny_jpeg_claiming_a_huge_size_is_refused_before_decoding() {
    let path = fuzz_file("jpeg-10280x10280-slow.jpg");
    let (r, took) = timed(|| load_linear_rgb(&path));
    expect_err_with(r, "10280x10280");
    assert!(took.as_secs_f64() < 1.0, "took {took:?}");

    let mut bytes = std::fs::read(&path).unwrap();
    let sof = bytes.windows(2).position(|w| w == [0xFF, 0xC0]).unwrap();
    bytes[sof + 5..sof + 9].copy_from_slice(&[0x20, 0, 0x20, 0]); // 8192 high, 8192 wide
    let (r, took) = timed(|| brume::io::image::decode_linear_rgb(&bytes, "8192.jpg"));
    expect_err_with(r, "8192x8192 pixels, which need at least 65536 bytes");
    assert!(took.as_secs_f64() < 1.0, "took {took:?}");
}

// sky_mask fuzzer, 1.27 million runs in: a palette PNG whose PLTE chunk is 521 bytes, not
// a multiple of 3, made png 0.18.1 panic building its colour table (slice index out of
// range; image-rs/image-png#694). The colour image and depth loaders go through the same
// decoder, so they refused it with the same panic.
#[test]
fn png_palette_of_partial_entries_is_refused() {
    use brume::io::mask::{decode_sky_mask, SkyMaskFormat};

    let bytes = std::fs::read(fuzz_file("sky-mask-plte-521-bytes.bin")).unwrap();
    // Byte 0 picks the format (0: binary), the rest is the PNG.
    assert_eq!(bytes[0], 0);
    let png = &bytes[1..];
    let needle = "PNG palette (PLTE chunk) of 521 bytes";
    expect_err_with(decode_sky_mask(png, "m.png", SkyMaskFormat::Binary), needle);
    expect_err_with(brume::io::image::decode_linear_rgb(png, "c.png"), needle);
    expect_err_with(
        brume::io::depth::load_range_from_bytes(
            png,
            Path::new("d.png"),
            &DepthOptions::default(),
            None,
        ),
        needle,
    );
}

// Found by reading, not by a fuzzer: the transmittance map's loader (`--transmittance-map`)
// and the left-right check's second read of a Cityscapes disparity decoded with the image
// crate directly, past the checks above, and the same palette (here with valid CRCs, which
// the sky mask's file lacks) made `brume render` panic. Now both go through brume's
// decoder: an error naming the file, and no output.
#[test]
fn transmittance_map_with_a_palette_of_partial_entries_is_refused() {
    let path = fuzz_file("transmittance-map-plte-521-bytes.png");
    let needle = "PNG palette (PLTE chunk) of 521 bytes";
    expect_err_with(brume::compat::load_optical_depth(&path), needle);
    let name = "transmittance-map-plte-521-bytes.png";
    crate::common::assert_render_refuses("--transmittance-map", &path, &[name, needle]);
}

// colour_image fuzzer, 2026-12-03 (2.6 M runs from the seeds): a 697-byte EXR of
// B44-compressed half channels. exr 1.74.2's `unpack14` computes `s[0] + delta - bias` in
// u32 and truncates to u16, as OpenEXR's C does in wrapping unsigned arithmetic; with
// overflow checks on (every debug and test build) the subtraction panicked, in exr's
// decompressor thread, where a panic aborts the whole process. The wrap is the format's:
// exr is built without overflow checks in every profile (Cargo.toml), as in release, where
// this file decodes to values brume then refuses by pixel.
#[test]
fn b44_exr_whose_deltas_wrap_is_decoded_as_openexr_does() {
    let path = fuzz_file("colour-exr-b44-wrapping-delta.exr");
    let bytes = std::fs::read(&path).unwrap();
    let name = "colour-exr-b44-wrapping-delta.exr";
    let r = brume::io::image::decode_linear_rgb(&bytes, name);
    expect_err_with(r, "colour value NaN at pixel (0, 0)");
}

// exr fuzzer, 2026-12-03, about 38 000 runs after seeds of each compression that really
// compress (32x32 ramps): a 1,199-byte DWAA EXR. exr 1.74.2's DWA decoder (new in 1.74)
// passes the size a block's header claims to zlib as the buffer to allocate; this one
// claims 1.7 PB, the allocation fails and the process aborts, in release builds too. Every
// DWA block's claims are now checked against its pixels before exr decodes any.
#[test]
fn dwa_block_claiming_petabytes_is_refused_before_decoding() {
    let path = fuzz_file("depth-exr-dwa-claims-1.7-petabytes.exr");
    let needle = "claims 1688849860268032 bytes of raw channel data, more than the 4096";
    let opts = DepthOptions::default();
    expect_err_with(load_range(&path, &opts), needle);
    let bytes = std::fs::read(&path).unwrap();
    expect_err_with(brume::io::image::decode_linear_rgb(&bytes, "d.exr"), needle);
    crate::common::assert_render_refuses("--depth", &path, &[needle, "corrupt"]);
}
