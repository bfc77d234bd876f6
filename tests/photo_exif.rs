//! A photo's EXIF carried to its PNG and JPEG outputs (`render`, `batch`): the camera,
//! the date and the place as they were, the orientation 1 (the pixels are written
//! upright), the pixel dimensions the output's, no thumbnail (it shows the photo without
//! fog); a broken block left out with a warning. The fixtures are ExifTool's
//! (`tests/data/exif/`, `tools/photo_metadata_fixtures.py`); outputs are read back by
//! kamadak-exif, which brume's writer does not use.

use std::path::{Path, PathBuf};

use exif::{In, Tag};
use image::ImageDecoder;

use crate::common::{self, brume, stderr};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/exif")
        .join(name)
}

/// The EXIF an image file carries, as its decoder reads it (JPEG APP1, PNG `eXIf`),
/// parsed.
fn exif_of(path: &Path) -> Option<exif::Exif> {
    let block = common::image_decoder(path).exif_metadata().unwrap()?;
    Some(exif::Reader::new().read_raw(block).unwrap())
}

fn text(exif: &exif::Exif, tag: Tag) -> String {
    let field = exif.get_field(tag, In::PRIMARY);
    field
        .map(|f| f.display_value().to_string())
        .unwrap_or_default()
}

fn uint(exif: &exif::Exif, tag: Tag) -> Option<u32> {
    exif.get_field(tag, In::PRIMARY)?.value.get_uint(0)
}

fn range(dir: &Path, w: usize, h: usize) {
    common::write_flat_range(dir, w, h);
}

fn render(dir: &Path, image: &Path, out: &str) -> String {
    common::render_over_range(dir, image, out, &["--beta", "0.05"])
}

/// Asserts what the fixtures' tags say, and the output's size and upright orientation.
fn assert_carried(exif: &exif::Exif, width: u32, height: u32) {
    assert_eq!(text(exif, Tag::Make), "\"brume test\"");
    assert_eq!(text(exif, Tag::Model), "\"fixture\"");
    assert_eq!(text(exif, Tag::DateTimeOriginal), "2026-07-14 06:30:00");
    assert!(exif.get_field(Tag::GPSLatitude, In::PRIMARY).is_some());
    assert_eq!(uint(exif, Tag::Orientation), Some(1));
    assert_eq!(uint(exif, Tag::PixelXDimension), Some(width));
    assert_eq!(uint(exif, Tag::PixelYDimension), Some(height));
    assert!(
        exif.fields().all(|f| f.ifd_num != In::THUMBNAIL),
        "no thumbnail IFD"
    );
}

/// A photo stored turned (Orientation 6) with a thumbnail: its JPEG and PNG outputs are
/// upright, 16 x 24, and say so; camera, date and place kept, thumbnail dropped.
#[test]
fn outputs_carry_the_photos_exif_upright() {
    let dir = tempfile::tempdir().unwrap();
    range(dir.path(), 24, 16);
    let source = exif_of(&fixture("rot6.jpg")).unwrap();
    assert_eq!(uint(&source, Tag::Orientation), Some(6));
    assert!(source.fields().any(|f| f.ifd_num == In::THUMBNAIL));
    for out in ["out.jpg", "out.png"] {
        let log = render(dir.path(), &fixture("rot6.jpg"), out);
        assert!(!log.contains("EXIF"), "{log}");
        let path = dir.path().join(out);
        assert_eq!(image::image_dimensions(&path).unwrap(), (16, 24));
        assert_carried(&exif_of(&path).expect("EXIF carried"), 16, 24);
    }
}

/// A big-endian block (Motorola order, as many cameras write) is edited in its own
/// order.
#[test]
fn a_big_endian_block_is_carried() {
    let dir = tempfile::tempdir().unwrap();
    range(dir.path(), 16, 8);
    render(dir.path(), &fixture("big-endian.png"), "out.jpg");
    assert_carried(&exif_of(&dir.path().join("out.jpg")).unwrap(), 16, 8);
}

/// A block cut inside its first IFD: the render goes on, the output has no EXIF, a
/// warning names the output.
#[test]
fn a_broken_block_is_left_out_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    range(dir.path(), 24, 16);
    let log = render(dir.path(), &fixture("broken.jpg"), "out.jpg");
    assert!(log.contains("out.jpg") && log.contains("EXIF"), "{log}");
    assert!(exif_of(&dir.path().join("out.jpg")).is_none());
}

/// `batch` carries it too: its output is `render`'s bytes.
#[test]
fn batch_outputs_carry_it_too() {
    let dir = tempfile::tempdir().unwrap();
    range(dir.path(), 24, 16);
    std::fs::copy(fixture("rot6.jpg"), dir.path().join("p.jpg")).unwrap();
    render(dir.path(), Path::new("p.jpg"), "render.png");
    std::fs::write(dir.path().join("m.csv"), "image,depth\np.jpg,r.pfm\n").unwrap();
    let batch = [
        "batch",
        "--manifest",
        "m.csv",
        "--out",
        "o",
        "--beta",
        "0.05",
        "--depth-kind",
        "range",
        "--depth-scale",
        "1",
    ];
    let run = brume(dir.path(), &batch);
    assert!(run.status.success(), "{}", stderr(&run));
    let out = dir.path().join("o/p_foggy_beta_0.05.png");
    assert_carried(&exif_of(&out).unwrap(), 16, 24);
    assert!(std::fs::read(out).unwrap() == std::fs::read(dir.path().join("render.png")).unwrap());
}
