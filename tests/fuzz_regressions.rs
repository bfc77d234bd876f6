//! Inputs the fuzzers in `fuzz/` found crashing a loader, kept as files in
//! `tests/data/fuzz/` and replayed on stable Rust: each must now give its expected result
//! without a panic or an abort. Also checks that the fuzzers' seeds in `fuzz/seeds/` are
//! files the loaders accept, so that fuzzing starts from inputs that reach deep into each
//! decoder.

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
    for target in ["pfm", "exr", "tiff", "npy"] {
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
        assert!(load_linear_rgb(&path).is_ok(), "{}", path.display());
        checked += 1;
    }
    assert!(checked >= 15, "only {checked} seeds");
}
